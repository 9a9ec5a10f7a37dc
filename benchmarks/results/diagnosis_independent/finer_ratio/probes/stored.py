# The stored diagnoses every probe here reads: ``cases(dirs)`` yields ``(case, truth, named, diagnosis)`` for each
# <dir>/<case>/diagnosis/diagnosis.json (with <dir>/<case>/truth.json), a case in a later dir replacing an earlier
# one's; ``truth`` and ``named`` are sets of ``key(effect, target)``.
import glob, json, os


def key(e, t):
    return e if e in ('action_delay', 'none') else f'{e}@{t}'


def cases(dirs):
    seen = {}
    for d in dirs:
        for f in sorted(glob.glob(os.path.join(d, '*', 'diagnosis', 'diagnosis.json'))):
            seen[f.split(os.sep)[-3]] = f
    for case, f in sorted(seen.items()):
        tr = json.load(open(os.path.join(os.path.dirname(os.path.dirname(f)), 'truth.json')))
        d = json.load(open(f))
        yield (case, {key(e, t) for e, t, _ in tr['effects']},
               {key(s['effect'], s['target']) for s in d['selected'] if s['effect'] != 'none'}, d)
