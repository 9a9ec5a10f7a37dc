"""The three DFKI pendulum folders run again (fifty-sixth session: the stamps resampled), each printed beside
its committed diagnosis.json. ``PYTHONPATH=. python benchmarks/results/real_datasets/rerun_dfki.py`` (2-core CPU, ~1 min;
writes to /tmp/scan/dfki)."""
import dataclasses, json, sys
from sim2real.sysid.diagnose import DiagnoseConfig, diagnose
D = "sim2real/sysid/data/dfki_pendulum/"
M = D + "pendulum.xml"
runs = {"dfki_pendulum": ((D + "energy_shaping.csv",), (D + "sac.csv",), {}),
        "dfki_pendulum_swapped": ((D + "sac.csv",), (D + "energy_shaping.csv",), {}),
        "dfki_pendulum_torque_offset": ((D + "energy_shaping.csv",), (D + "sac.csv",), "offset")}
for name, (tr, ho, extra) in runs.items():
    cfg = DiagnoseConfig(model=M, recordings=tr, heldout=ho, out=f"/tmp/scan/dfki/{name}", overwrite=True,
                         plots=name != "dfki_pendulum_torque_offset", progress=False)
    if extra == "offset":
        cfg = dataclasses.replace(cfg, effects=tuple(cfg.effects) + ("torque_offset",))
    d = diagnose(cfg)
    old = json.load(open(f"benchmarks/results/real_datasets/{name}/diagnosis.json"))
    for x, tag in ((old, "old"), (d, "new")):
        print(name, tag, x["answer"], [(s["effect"], s["target"], {k: round(v, 4) for k, v in s["params"].items()}) for s in x["selected"]],
              round(x["fit"]["before"], 5), round(x["fit"]["after"], 5), x["fit"]["change"],
              (x.get("energy") or {}).get("named"), flush=True)
