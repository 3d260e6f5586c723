#!/usr/bin/python3
# Energy trend and fluctuation of bench/contact_energy/run.sh's runs, per system, h and variant:
# trend = slope of a line through 20 block means of E x the run's length; fluctuation = standard
# deviation of E about that line; mean over the starts +- standard error, trend/se and
# trend/fluctuation; then the runs with a landing deficit (a contact step whose energy could
# not be given back: a jump, not a drift) and the trend over the others. Usage: analyse.py OUTDIR
import collections
import csv
import glob
import sys

import numpy as np

D = sys.argv[1] if len(sys.argv) > 1 else '/tmp/contact_energy'
BLOCKS = 20
runs = collections.defaultdict(list)
for name in sorted(glob.glob(D + '/*.csv')):
    system, variant, h, _ = name.split('/')[-1][:-4].split('_')
    rows = list(csv.DictReader(open(name)))
    t = np.array([float(r['time']) for r in rows])
    e = np.array([float(r['total']) for r in rows])
    e -= e[0]
    k = len(t) // BLOCKS
    tb = t[:k * BLOCKS].reshape(BLOCKS, k).mean(1)
    eb = e[:k * BLOCKS].reshape(BLOCKS, k).mean(1)
    slope, level = np.polyfit(tb, eb, 1)
    trend = slope * (t[-1] - t[0])
    fluctuation = np.std(e - (level + slope * t))
    contacts = sum(float(r['reflected']) for r in rows)
    gap = min(float(r['min_gap']) for r in rows)
    deficits = sum(float(r['landing_deficits']) for r in rows)
    runs[(system, float(h), variant)].append((trend, fluctuation, contacts, gap, deficits))
print('| system | h | variant | trend +- se | trend/se | fluctuation | trend/fluctuation | contacts/run | min gap '
      '| runs with deficits | trend without them (/fluctuation) |')
print('|---|---|---|---|---|---|---|---|---|---|---|')
for (system, h, variant), r in sorted(runs.items()):
    trend = np.array([x[0] for x in r])
    fluctuation = np.mean([x[1] for x in r])
    mean = trend.mean()
    se = trend.std(ddof=1) / np.sqrt(len(trend)) if len(trend) > 1 else float('nan')
    print(f'| {system} | {h:g} | {variant} | {mean:+.2e} +- {se:.1e} | {mean / se:+.1f} | '
          f'{fluctuation:.2e} | {mean / fluctuation:+.2f} | {np.mean([x[2] for x in r]):.0f} | '
          f'{min(x[3] for x in r):.1e} | ', end='')
    clean = np.array([x[0] for x in r if x[4] == 0])
    clean_se = clean.std(ddof=1) / np.sqrt(len(clean)) if len(clean) > 1 else float('nan')
    clean_mean = clean.mean() if len(clean) else float('nan')
    print(f'{len(trend) - len(clean)} of {len(trend)} | {clean_mean:+.2e} +- {clean_se:.1e} '
          f'({clean_mean / fluctuation:+.2f}) |')
