"""Medians over rounds of `hapto bench tick --repeats N` outputs, two builds or settings side by
side: each motion's own p50, p99.9 and max (us) as `A -> B`, the range over the rounds, and each
round's B / A ratio.

    python3 own_medians.py DIR PREFIX A B ROUNDS

reads DIR/PREFIX-A-rK.txt and DIR/PREFIX-B-rK.txt for each K in ROUNDS (comma-separated), e.g.
`python3 own_medians.py friction-from-free/final s6 main new2 2,3,4,5` in this directory."""

import statistics
import sys


def own_columns(path):
    """Each motion's own p50, p99.9 and max (ns) from the bench's first table."""
    rows = {}
    in_table = False
    for line in open(path):
        if line.startswith("motion ") and "own p50" in line:
            in_table = True
            continue
        if in_table and not line.strip():
            in_table = False
        if in_table and "|" in line:
            parts = line.split("|")
            own = parts[3].split()
            rows[parts[0].split()[0]] = (int(own[0]), int(own[2]), int(own[3]))
    return rows


def main(directory, prefix, a, b, rounds):
    ks = [int(k) for k in rounds.split(",")]
    runs = {x: [own_columns(f"{directory}/{prefix}-{x}-r{k}.txt") for k in ks] for x in (a, b)}
    for motion in runs[a][0]:
        cells = [motion]
        for col, name in enumerate(("p50", "p99.9", "max")):
            xs = [run[motion][col] / 1000 for run in runs[a]]
            ys = [run[motion][col] / 1000 for run in runs[b]]
            ratios = " / ".join(f"{y / x:.2f}" for x, y in zip(xs, ys))
            cells.append(
                f"{name} {statistics.median(xs):.2f} ({min(xs):.2f}-{max(xs):.2f}) -> "
                f"{statistics.median(ys):.2f} ({min(ys):.2f}-{max(ys):.2f}) [{ratios}]")
        print(" | ".join(cells))


if __name__ == "__main__":
    if len(sys.argv) != 6:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    main(*sys.argv[1:])
