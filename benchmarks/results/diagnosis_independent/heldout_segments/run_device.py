"""Every tuning list's cases under one or more diagnosis settings, in one pool over all the host's
CPU cores (JAX on CPU, one case per core), each finished (case, setting) written at once as one
JSON line to ``OUT/<setting>.jsonl`` (so a run cut short by the time limit keeps what finished).

    python run_device.py OUT SECONDS [LIST ...]

Settings (``SETTINGS``, name -> ``DiagnoseConfig`` overrides): ``base``, the defaults, or the
JSON object in the environment's ``SETTINGS`` (``{"base": {}, "prune15": {"prune_t": 1.5}}``);
``CASES``: a file of case labels, one per line, to run only those of the lists. The
settings of a case run next to each other, the two-effect lists first (the longest cases). A
line holds what the held-out walk and the selection need offline: the steps with each held-out
segment's error (``heldout_segments``), the model file's (``per_segment_before``), every round's
candidates and the validation errors per segment their test compared (``round_tests``)."""
import json
import os
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", ".."))
import diagnosis_independent as di  # noqa: E402
import sysid_cases  # noqa: E402

SETTINGS = json.loads(os.environ.get("SETTINGS") or '{"base": {}}')
ONLY = set(open(os.environ["CASES"]).read().split()) if os.environ.get("CASES") else None
LISTS = ("combos", "pairs", "tuning", "extra", "focus", "servo", "beside", "timing", "pd")


CURRENT = {"label": "?"}  # the case a worker is on (for hooks that log what it computes)


def one(case, name: str) -> str:
    CURRENT["label"] = case.label
    work = f"/tmp/w_{name}"
    row = di.run_case(case, work, SETTINGS[name])
    folder = os.path.join(work, case.label)
    out = {"case": case.label, "split": case.split, "kind": case.kind, "setting": name,
           "truth": sorted(di.truth_keys(case)), "named": row.get("named"), "correct": row.get("correct"),
           "seconds": row.get("seconds"), "answer": row.get("answer")}
    try:
        d = json.load(open(os.path.join(folder, "diagnosis", "diagnosis.json")))
        desc = json.load(open(os.path.join(folder, "truth.json")))
    except OSError:
        return json.dumps(out)
    out.update(named=di.named_keys(d), param_errors=di._param_errors(desc, d), before=d["fit"]["before"],
               after=d["fit"]["after"], per_segment_before=d["fit"].get("per_segment_before"), steps=d["steps"],
               pruned=[n for n in d.get("notes", []) if " dropped: " in n],
               rounds=[[{k: c.get(k) for k in ("effect", "target", "screen_score", "passed", "objective",
                                                 "validation_ratio", "t", "params")}
                        for c in r["candidates"]] for r in d.get("rounds", [])])
    # what replaying each round's test needs (added after the run in device/, whose lines lack it)
    out["round_tests"] = [{"base": r.get("base"), "base_validation_segments": r.get("base_validation_segments"),
                           "validation_segments": [c.get("validation_segments") for c in r["candidates"]],
                           "base_level": [c.get("base_level") for c in r["candidates"]]}
                          for r in d.get("rounds", [])]
    return json.dumps(out)


def main(out: str, seconds: float, lists: list[str]):
    import jax

    jax.config.update("jax_num_cpu_devices", 1)  # (JAX not started here: the workers fork)
    end = time.time() + seconds
    jobs = [(c, s) for split in lists for c in sysid_cases.split_cases(split) for s in SETTINGS
            if ONLY is None or c.label in ONLY]
    os.makedirs(out, exist_ok=True)
    files = {s: open(os.path.join(out, f"{s}.jsonl"), "a") for s in SETTINGS}
    n = os.cpu_count() or 1
    print(f"{len(jobs)} runs on {n} processes, {seconds:.0f} s", flush=True)
    done = 0
    with ProcessPoolExecutor(n) as ex:
        pending = {ex.submit(one, c, s): (c.label, s) for c, s in jobs}
        while pending and time.time() < end:
            fin, _ = wait(pending, timeout=max(1.0, end - time.time()), return_when=FIRST_COMPLETED)
            for f in fin:
                label, s = pending.pop(f)
                try:
                    files[s].write(f.result() + "\n")
                    files[s].flush()
                except Exception as e:  # noqa: BLE001
                    print(f"{label} {s}: {type(e).__name__}: {e}", flush=True)
                done += 1
        print(f"{done} of {len(jobs)} finished in {seconds - (end - time.time()):.0f} s", flush=True)
        for f in pending:
            f.cancel()
        for p in list(ex._processes.values()):  # the workers still running are cut, not waited for
            p.kill()
        os._exit(0)


def cli() -> None:
    """``python SCRIPT OUT SECONDS [LIST ...]``"""
    main(sys.argv[1], float(sys.argv[2]), sys.argv[3:] or list(LISTS))


if __name__ == "__main__":
    cli()
