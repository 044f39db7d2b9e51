"""Load against device count from Python: each count of simulated hands runs 5 times for 0.5 s
over the default scene; the plot shows the median total load with the min..max range of the
repeats as error bars. Run from a build tree:
    PYTHONPATH=build/release/python python3 docs/python-example.py docs/results/python-example.png
(The load is measured on the wall clock: in step mode the ticks take no session time, so
their load reads 0; step mode is for results that must repeat exactly.)"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy

import hapto

scene, counts, repeats = hapto.default_scene(), range(1, 9), 5
loads = numpy.zeros((len(counts), repeats))
for i, n in enumerate(counts):
    hands = [{"name": "hand%d" % k, "kind": "sim"} for k in range(n)]
    for r in range(repeats):
        with hapto.Session(scene, devices=hands) as session:
            session.run(0.5)
            loads[i, r] = 100 * session.stop()["total"]["load_sum"]
median = numpy.median(loads, axis=1)
low, high = median - loads.min(axis=1), loads.max(axis=1) - median
plt.errorbar(list(counts), median, yerr=[low, high], fmt="o-", capsize=4, label="median, min..max")
plt.xlabel("simulated hands (1 kHz each)")
plt.ylabel("total load (% of one core)")
plt.title("hapto %s: load against device count, %d runs of 0.5 s each" % (hapto.__version__, repeats))
plt.ylim(bottom=0)
plt.legend()
plt.savefig(sys.argv[1] if len(sys.argv) > 1 else "python-example.png", dpi=100)
