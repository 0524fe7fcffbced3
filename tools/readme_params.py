#!/usr/bin/env python3
# Prints the README's planner parameter list from the parameter table, as `gdrhcr_sim --help` gives it:
#   build/src/gdrhcr_sim --help | python3 tools/readme_params.py
# (paste between the README's <!-- planner parameters --> markers; a core test checks the list.)
import sys, re, collections
planner = None; rows = collections.OrderedDict(); rules = []; mode = None
for line in sys.stdin:
    m = re.match(r'--planner (\S+) parameters', line)
    if m: planner = m.group(1); mode = 'p'; continue
    if line.startswith('rules:'): mode = 'r'; continue
    if mode == 'p':
        m = re.match(r'  --(\S+) (\[[^\]]*\]|\S+), default (.*?): (.*)', line.rstrip('\n'))
        if m:
            name, rng, d, mean = m.groups()
            r = rows.setdefault(name, {'range': rng, 'mean': mean, 'd': collections.OrderedDict()})
            r['d'][planner] = d
    elif mode == 'r' and line.startswith('  '):
        rules.append(line.strip())
out = ['<!-- planner parameters -->',
       '| parameter | range | default per planner (rule; paper preset) | meaning |', '|---|---|---|---|']
bar = '\\|'
for name, r in rows.items():
    ds = list(r['d'].items())
    d = ('all: ' + ds[0][1]) if len(ds) == 3 and len(set(v for k, v in ds)) == 1 else '; '.join(k + ': ' + v for k, v in ds)
    out.append('| `--%s` | %s | %s | %s |' % (name, r['range'].replace('|', bar), d, r['mean']))
out.append('')
out.append("Rules (defaults picked from the map and the fleet; the figures behind them: `docs/results.md`, \"The product default's rules\"):")
for x in rules:
    n, w = x.split(': ', 1); out.append('- `%s`: %s' % (n, w))
out.append('<!-- /planner parameters -->')
print('\n'.join(out))
