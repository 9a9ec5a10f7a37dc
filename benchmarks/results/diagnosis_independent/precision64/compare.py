"""f32 against f64 rows of device/: ``python compare.py`` (prints the table of the README)."""
import collections
import gzip
import json
import os
import statistics

HERE = os.path.dirname(os.path.abspath(__file__))
rows = {}
for s in ("f32", "f64"):
    for line in gzip.open(os.path.join(HERE, "device", f"{s}.jsonl.gz"), "rt"):
        d = json.loads(line)
        rows.setdefault(d["case"], {})[s] = d
both = sorted(c for c in rows if len(rows[c]) == 2)
print(f"{len(both)} cases run in both settings")
right = collections.Counter()
for c in both:
    a, b = rows[c]["f32"], rows[c]["f64"]
    for s, r in (("f32", a), ("f64", b)):
        right[(a["split"], a["kind"], s)] += bool(r["correct"])
    right[(a["split"], a["kind"], "n")] += 1
    if a["named"] != b["named"]:
        print(f"  {c}: f32 {' + '.join(a['named']) or 'none'} ({'right' if a['correct'] else 'wrong'}) -> "
              f"f64 {' + '.join(b['named']) or 'none'} ({'right' if b['correct'] else 'wrong'})")
print("| list | kind | cases | right in f32 | right in f64 |\n|---|---|---|---|---|")
for split, kind in sorted({(k[0], k[1]) for k in right}):
    print(f"| {split} | {kind} | {right[(split, kind, 'n')]} | {right[(split, kind, 'f32')]} | {right[(split, kind, 'f64')]} |")
t32 = [rows[c]["f32"]["seconds"] for c in both]
t64 = [rows[c]["f64"]["seconds"] for c in both]
print(f"seconds per case, median: f32 {statistics.median(t32):.1f}, f64 {statistics.median(t64):.1f}; "
      f"sum {sum(t32):.0f} against {sum(t64):.0f} ({sum(t64) / sum(t32):.2f}x)")
