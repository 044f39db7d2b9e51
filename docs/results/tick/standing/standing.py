"""Issue 39 item 2, where it stands, from run.sh's output: each motion's own p50, p99.9 and max
(us; median of the rounds and their range), its own p99.9 over rest's of the same run, and the
10^6-triangle sphere against the 10^3 one (same index), per round.

    python3 standing.py DIR ROUNDS SPHERE_ROUNDS

reads DIR/all-rK.txt for each K in ROUNDS and DIR/s6-rK.txt and DIR/s3-rK.txt for each K in
SPHERE_ROUNDS (comma-separated: the rounds without a slow spell)."""

import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from own_medians import own_columns  # noqa: E402  (one reader of the bench's table)


def cell(values):
    return f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


def summary(runs):
    for motion in runs[0]:
        cols = [[run[motion][c] / 1000 for run in runs] for c in range(3)]
        over_rest = [run[motion][1] / run["rest"][1] for run in runs]
        print(f"| {motion} | {cell(cols[0])} | {cell(cols[1])} | {cell(cols[2])} | "
              f"{cell(over_rest)}x |")


def main(directory, rounds, sphere_rounds):
    def read(prefix, ks):
        return [own_columns(f"{directory}/{prefix}-r{k}.txt") for k in ks.split(",")]

    print("| motion | own p50 | own p99.9 | own max | own p99.9 / rest's |")
    summary(read("all", rounds))
    fine, coarse = read("s6", sphere_rounds), read("s3", sphere_rounds)
    print("10^6-triangle sphere, octree:8:0.00028:")
    summary(fine)
    print("10^3-triangle sphere, octree:8:0.00028:")
    summary(coarse)
    for col, name in ((0, "p50"), (1, "p99.9")):
        ratios = [f["sphere"][col] / c["sphere"][col] for f, c in zip(fine, coarse)]
        print(f"10^6 / 10^3 own {name}, per round: " + " / ".join(f"{r:.2f}" for r in ratios))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    main(*sys.argv[1:])
