"""Where the slowest ticks of a motion go, phase by phase, from the probes of probes.patch.

    HAPTO_DIAG=diag-sweep.txt hapto bench tick --motion sweep --ticks 20000 --repeats 5
    python3 tail_phases.py diag-sweep.txt [REPEATS]

The file holds a line per tick and repeat (the repeats one after another, the ticks in the same
order each time): 14 phase times (ns) and 8 counts (see probes.patch, Diag.h). Each tick is
taken from the repeat with its least total; prints the mean phases of the typical ticks (within
30 ns of the median) and of the ticks at or above the own p99.9."""

import sys

import numpy as np


def show(y, label):
    ph = y[:, :14].mean(0)
    c = y[:, 14:].mean(0)
    update = ph[:6].sum()
    print("  %s: %d ticks, total %.0f | near %.0f start %.0f resting %.0f free %.0f "
          "friction %.0f (anchor scan %.0f) finish %.0f | walks %.0f slide %.0f other %.0f"
          % (label, len(y), ph[9], ph[0], ph[1], ph[2], ph[3], ph[4], ph[6], ph[5], ph[7],
             ph[8], ph[9] - update - ph[7] - ph[8]))
    print("    per tick: free passes %.1f, friction passes %.1f, near objects %.1f, covered "
          "scans %.1f, sweeps %.1f, narrow tests %.1f, solves %.2f, extra leaves %.2f" % tuple(c))
    print("    in the passes: closest point %.0f, sweeps %.0f, after a hit %.0f, after none %.0f"
          % tuple(ph[10:14]))


def main():
    path = sys.argv[1]
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    a = np.loadtxt(path)
    n = len(a) // repeats
    b = a[: n * repeats].reshape(repeats, n, -1)
    best = b[:, :, 9].argmin(0)
    x = b[best, np.arange(n)]
    total = x[:, 9]
    q = np.quantile(total, 0.999)
    print("own p50 %.0f ns, own p99.9 %.0f ns" % (np.median(total), q))
    show(x[np.abs(total - np.median(total)) < 30], "typical")
    show(x[total >= q], "at or above p99.9")


if __name__ == "__main__":
    main()
