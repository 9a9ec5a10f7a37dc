# masscap/compare_all.py LOG...: every case of the mass cap's runs (logs named <list>[_...].log) against
# each list's latest stored answers with steps 69 and 70's moves. ``compare`` also serves
# ties_2core/compare.py (step 70's replay, against the answers before it).
import csv, os, re, sys
R = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + '/'


def rd(p): return {r['case']: r for r in csv.DictReader(open(p))}


def fromlogs(paths):
    out = {}
    for p in paths:
        for line in open(p):
            m = re.match(r'^(OK |-- )(\S+)\s+named (.+?)\s+[0-9.]+s', line)
            if m: out[m.group(2)] = {'case': m.group(2), 'named': m.group(3).strip(), 'correct': str(m.group(1) == 'OK ')}
    return out


def latest():
    """Each tuning list's latest stored answers before step 69."""
    return {
     'combos': rd(R + 'combos_before_device/cases.csv'),
     'timing': rd(R + 'timing_before_2core/cases.csv'),
     'extra': rd(R + 'finer_refit/extra_2core/cases.csv'),
     'tuning': rd(R + 'finer_refit/tuning_refit_only_2core/cases.csv'),
     'focus': rd(R + 'focus_masses_2core/cases.csv'),
     'beside': rd(R + 'finer_refit/beside_device/cases.csv'),
     'servo': rd(R + 'finer_refit/servo_device/cases.csv'),
     'pairs': fromlogs([R + 'finer_refit/pairs_2core_last20.log', R + 'finer_refit/pairs_device_first16_cut.log']),
    }


STEP69 = {  # band_shown/bottom_device
 '6027_arm2_coulomb_friction@elbow+mass_offset@upper': ('coulomb_friction@elbow + mass_offset@upper', 'True'),
 '6050_pendubot_coulomb_friction@j_act+mass_offset@first': ('mass_offset@first + coulomb_friction@j_act', 'True'),
 '3054_belt_stage_backlash@voltage': ('none', 'False'),
 '3535_filtered_drive_backlash@amp+coulomb_friction@shaft': ('coulomb_friction@shaft', 'False'),
}
STEP70 = {  # ties_2core/changes.txt
 '6103_ball_screw_coulomb_friction@screw+action_delay': ('backlash@motor', 'False'),
 '6131_filtered_drive_coulomb_friction@shaft+action_delay': ('coulomb_friction@shaft + action_delay', 'True'),
 '3925_linear_axis_action_delay': ('action_delay', 'True'),
}


def compare(logs, over):
    """Print every answer of ``logs`` ({list: [log paths]}) that differs from the list's stored one
    (``over``: {case: (named, correct)} moves of later steps), then each list's net change."""
    base, tot, runs = latest(), {}, {}
    for s, paths in logs.items():
        new = fromlogs(paths)
        runs[s] = runs.get(s, 0) + len(new)
        for c, r in new.items():
            nb, cb = over.get(c, (base[s][c]['named'], base[s][c]['correct']))
            if r['named'] != nb:
                d = (r['correct'] == 'True') - (cb == 'True')
                print(f"{s:7s} {c:62s} {nb} [{cb}] -> {r['named']} [{r['correct']}]  {d:+d}")
                tot[s] = tot.get(s, 0) + d
    for s in runs:
        print(f"# {s}: {runs[s]} run, net {tot.get(s, 0):+d}")


if __name__ == '__main__':
    logs = {}
    for log in sys.argv[1:]:
        logs.setdefault(os.path.basename(log)[:-4].split('_')[0], []).append(log)  # (extra_cut.log: extra)
    compare(logs, {**STEP69, **STEP70})
