"""Medians of the rounds' own p50, p99.9 and max (us), warm start off -> on, with each round's
ratio: python3 medians.py PREFIX ROUNDS, e.g. `python3 medians.py s6 2,3,4,5` in this directory
(files PREFIX-off-rN.txt and PREFIX-on-rN.txt (HAPTO_WARM unset and set))."""
import sys, statistics as st
def own(f):
    rows={}
    t=False
    for line in open(f):
        if line.startswith('motion ') and 'own p50' in line: t=True; continue
        if t and not line.strip(): t=False
        if t and '|' in line:
            parts=line.split('|'); m=parts[0].split()[0]; o=parts[3].split()
            rows[m]=(int(o[0]),int(o[2]),int(o[3]))
    return rows
def table(prefix, rounds, motions=None):
    for b in ('off','on'):
        pass
    data={b:[own(f'{prefix}-{b}-r{r}.txt') for r in rounds] for b in ('off','on')}
    ms = motions or list(data['off'][0].keys())
    for m in ms:
        out=[m]
        for k,name in enumerate(('p50','p99.9','max')):
            a=[d[m][k]/1000 for d in data['off']]; b=[d[m][k]/1000 for d in data['on']]
            ratios=[y/x for x,y in zip(a,b)]
            out.append(f"{name} {st.median(a):.2f} ({min(a):.2f}-{max(a):.2f}) -> {st.median(b):.2f} ({min(b):.2f}-{max(b):.2f}) [{' / '.join(f'{r:.2f}' for r in ratios)}]")
        print(' | '.join(out))
table(sys.argv[1], [int(x) for x in sys.argv[2].split(',')])
