#!/usr/bin/python3
# Where the energy of bench/contact_energy/run.sh's runs goes, from thermo written every step
# (STEP_THERMO=1): per system, h and variant, the change of Verlet's shadow energy S (thermo
# `shadow_energy`) summed over contact steps (reflected > 0), over the steps with a landing
# deficit, and over free (contact-free) steps; and, per isolated contact step (no other within
# 2W steps, W = 0.25 time units), the loss: mean S over steps W..2W after it less the mean
# over 2W..W before it (Verlet keeps its modified energy S~ between contacts, and away from
# the steep wall S~ - S is negligible, so this is the change of S~ the contact step made).
# Usage: attribute.py OUTDIR
import collections
import glob
import sys

import numpy as np

D = sys.argv[1] if len(sys.argv) > 1 else '/tmp/contact_energy'
sums = collections.defaultdict(lambda: np.zeros(4))
losses = collections.defaultdict(list)
for name in sorted(glob.glob(D + '/*.csv')):
    system, variant, h, _ = name.split('/')[-1][:-4].split('_')
    d = np.genfromtxt(name, delimiter=',', names=True)
    if len(d) > 1 and d['step'][1] - d['step'][0] != 1:
        sys.exit(f'{name}: thermo not written every step (run with STEP_THERMO=1)')
    S = d['shadow_energy']
    dS = np.diff(S)
    contact = d['reflected'][1:] > 0
    deficit = d['landing_deficits'][1:] > 0
    key = (system, float(h), variant)
    sums[key] += [dS[contact].sum(), dS[deficit].sum(), dS[~contact].sum(), 1]
    W = round(0.25 / float(h))
    steps = np.nonzero(contact)[0] + 1  # rows of S after each contact step
    for a, k, b in zip(np.r_[-10**9, steps[:-1]], steps, np.r_[steps[1:], 10**9]):
        if k - a > 2 * W and b - k > 2 * W and k >= 2 * W and k + 2 * W < len(S):
            losses[key].append(S[k + W:k + 2 * W].mean() - S[k - 2 * W:k - W].mean())
print('| system | h | variant | dS contact steps | of which deficit steps | dS free steps | '
      'isolated contacts | loss per contact +- se | summed |')
print('|---|---|---|---|---|---|---|---|---|')
for key, (c, dfc, free, runs) in sorted(sums.items()):
    loss = np.array(losses[key])
    se = loss.std(ddof=1) / np.sqrt(len(loss)) if len(loss) > 1 else float('nan')
    print(f'| {key[0]} | {key[1]:g} | {key[2]} | {c / runs:+.2e} | {dfc / runs:+.2e} | '
          f'{free / runs:+.2e} | {len(loss) / runs:.0f} | {loss.mean():+.2e} +- {se:.1e} | '
          f'{loss.sum() / runs:+.2e} |')
print('(sums per run, mean over the runs)')
