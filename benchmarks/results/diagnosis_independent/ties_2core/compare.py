import csv, glob, os, re
R = '/work/main/benchmarks/results/diagnosis_independent/'
def rd(p): return {r['case']: r for r in csv.DictReader(open(p))}
def fromlogs(paths):
    out = {}
    for p in paths:
        for line in open(p):
            m = re.match(r'^(OK |-- )(\S+)\s+named (.+?)\s+[0-9.]+s', line)
            if m: out[m.group(2)] = {'case': m.group(2), 'named': m.group(3).strip(), 'correct': str(m.group(1) == 'OK ')}
    return out
base = {
 'combos': rd(R + 'combos_before_device/cases.csv'),
 'timing': rd(R + 'timing_before_2core/cases.csv'),
 'extra': rd(R + 'finer_refit/extra_2core/cases.csv'),
 'tuning': rd(R + 'finer_refit/tuning_refit_only_2core/cases.csv'),
 'focus': rd(R + 'focus_masses_2core/cases.csv'),
 'beside': rd(R + 'finer_refit/beside_device/cases.csv'),
 'servo': rd(R + 'finer_refit/servo_device/cases.csv'),
 'pairs': fromlogs([R + 'finer_refit/pairs_2core_last20.log', R + 'finer_refit/pairs_device_first16_cut.log']),
}
# step 69's moves (band_shown/bottom_device)
over = {'6027_arm2_coulomb_friction@elbow+mass_offset@upper': ('coulomb_friction@elbow + mass_offset@upper', 'True'),
        '6050_pendubot_coulomb_friction@j_act+mass_offset@first': ('mass_offset@first + coulomb_friction@j_act', 'True'),
        '3054_belt_stage_backlash@voltage': ('none', 'False'),
        '3535_filtered_drive_backlash@amp+coulomb_friction@shaft': ('coulomb_friction@shaft', 'False')}
tot = {}
for log in sorted(glob.glob('/tmp/tie_out_*.log')):
    s = log.split('_')[-1][:-4]
    new = fromlogs([log])
    b = base[s]
    for c, r in new.items():
        nb, cb = over.get(c, (b[c]['named'], b[c]['correct']))
        if r['named'] != nb:
            print(f"{s:7s} {c:60s} {nb} [{cb}] -> {r['named']} [{r['correct']}]")
            d = (r['correct'] == 'True') - (cb == 'True')
            tot[s] = tot.get(s, 0) + d
    print(f"# {s}: {len(new)} run, net {tot.get(s, 0):+d}")
