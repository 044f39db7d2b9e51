#!/usr/bin/env python3
"""CPU per device-tick, kernel included, against the number of simulated hands in `hapto run`.

    many_devices.py HAPTO [--counts 1,8,32,64,128] [--per-thread 1,16] [--duration 12]
                          [--rate 1000] [--warm-us default,0,5] [--json OUT.json]

For every count N and every devices-per-thread K it writes a device file of N simulated hands
(script "walk", distinct seeds, spread 1 cm apart), runs

    HAPTO run --devices FILE --rate RATE --duration D --report R.json --quiet
              [--devices-per-thread K] [--warm-us W]

and reads, twice (4 s after the start, when the scene, the index and the opens are done and
TBB's workers have gone back to sleep, and 1 s before the end), the process's CPU time (user
and system, /proc/PID/stat: every thread, and the kernel's work on their behalf) and each
thread's run time (/proc/PID/task/TID/schedstat, in ns) and context switches. Over that window:

    cpu per device-tick   = process CPU / device ticks
    servo per device-tick = run time of the servo threads (those that wake at least rate / 2
                            times a second) / device ticks: the tick, the sleep and the wake-up
    tick itself           = the report's mean load x period (wake-up to force written)
    process share         = process CPU / window / cores
    other                 = the other threads' run time / window / cores (control thread,
                            supervisor, TBB workers, signals)

The servo CPU beyond the tick itself is the sleep and the wake-up: clock_nanosleep, the timer,
the scheduler and the two context switches per wake (voluntary switches per device-tick).
Device ticks in the window are the report's ticks scaled by window / duration. Runs are one at
a time, so two runs never share the cores; other processes on the machine still may.
"""

import argparse
import itertools
import json
import os
import subprocess
import sys
import tempfile
import time

CLK_TCK = os.sysconf("SC_CLK_TCK")
WARMUP_S = 4.0  # scene, index and opens done; TBB's workers asleep again


def device_file(path, count, rate):
    devices = []
    for i in range(count):
        # A 1 cm grid in the clear middle of the default scene, one hand per point.
        x, y, z = i % 8, (i // 8) % 4, i // 32
        devices.append({
            "name": f"h{i}",
            "kind": "sim",
            "rate_hz": rate,
            "transform": {"translation": [0.01 * (x - 3.5), 0.01 * (y - 1.5), 0.01 * (z - 1.5)]},
            "sim": {"script": "walk", "seed": i + 1},
        })
    with open(path, "w") as f:
        json.dump({"format": "hapto-devices", "version": 1, "devices": devices}, f)


def threads(pid):
    """Per thread: (user s, system s, run ns, voluntary, involuntary switches)."""
    out = {}
    for tid in os.listdir(f"/proc/{pid}/task"):
        try:
            with open(f"/proc/{pid}/task/{tid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            with open(f"/proc/{pid}/task/{tid}/schedstat") as f:
                run_ns = int(f.read().split()[0])
            voluntary = involuntary = 0
            with open(f"/proc/{pid}/task/{tid}/status") as f:
                for line in f:
                    if line.startswith("voluntary_ctxt_switches"):
                        voluntary = int(line.split()[1])
                    elif line.startswith("nonvoluntary_ctxt_switches"):
                        involuntary = int(line.split()[1])
        except (FileNotFoundError, ProcessLookupError):
            continue  # a thread that just ended
        # After the ')': utime and stime are fields 14 and 15 of proc(5), in clock ticks.
        out[tid] = (int(fields[11]) / CLK_TCK, int(fields[12]) / CLK_TCK, run_ns, voluntary,
                    involuntary)
    return out


def process_cpu(pid):
    """The whole process's user and system time (s), threads that ended included."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return int(fields[11]) / CLK_TCK, int(fields[12]) / CLK_TCK


def run_one(hapto, count, per_thread, warm_us, duration, rate, scratch):
    devices = os.path.join(scratch, f"devices-{count}.json")
    report = os.path.join(scratch, f"report-{count}-{per_thread}.json")
    device_file(devices, count, rate)
    cmd = [hapto, "run", "--devices", devices, "--rate", str(rate), "--duration", str(duration),
           "--report", report, "--quiet"]
    if per_thread != 1:
        cmd += ["--devices-per-thread", str(per_thread)]
    if warm_us is not None:
        cmd += ["--warm-us", str(warm_us)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    time.sleep(WARMUP_S)
    t0 = time.monotonic()
    u0, s0 = process_cpu(proc.pid)
    before = threads(proc.pid)
    time.sleep(duration - WARMUP_S - 1.0)
    t1 = time.monotonic()
    u1, s1 = process_cpu(proc.pid)
    after = threads(proc.pid)
    _, err = proc.communicate()
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed ({proc.returncode}): {err}")
    with open(report) as f:
        r = json.load(f)
    window = t1 - t0
    ticks = sum(d["ticks"] for d in r["devices"]) * window / r["total"]["duration_s"]
    cpu = (u1 - u0) + (s1 - s0)
    # Servo threads wake every period: at least half the rate's voluntary switches a second.
    # The rest: the control thread (5 ms), the supervisor (10 ms), TBB's workers, signals.
    servo_ns = other_ns = voluntary = involuntary = servo_threads = 0
    for tid, b in before.items():
        a = after.get(tid)
        if a is None:
            continue
        run = a[2] - b[2]
        if (a[3] - b[3]) / window >= rate / 2:
            servo_ns += run
            servo_threads += 1
            voluntary += a[3] - b[3]
            involuntary += a[4] - b[4]
        else:
            other_ns += run
    period_ns = 1e9 / rate
    tick_ns = sum(d["load"]["mean"] for d in r["devices"]) / count * period_ns
    return {
        "devices": count,
        "devices_per_thread": per_thread,
        "warm_us": warm_us,  # None: the runtime's default
        "servo_threads": servo_threads,
        "window_s": round(window, 3),
        "cpu_per_device_tick_us": round(cpu / ticks * 1e6, 3),
        "user_per_device_tick_us": round((u1 - u0) / ticks * 1e6, 3),
        "system_per_device_tick_us": round((s1 - s0) / ticks * 1e6, 3),
        "servo_cpu_per_device_tick_us": round(servo_ns / ticks / 1000, 3),
        "other_threads_cpu_share": round(other_ns / 1e9 / window / os.cpu_count(), 4),
        "tick_itself_us": round(tick_ns / 1000, 3),
        "process_share_of_cores": round(cpu / window / os.cpu_count(), 4),
        "servo_share_of_cores": round(servo_ns / 1e9 / window / os.cpu_count(), 4),
        "voluntary_switches_per_device_tick": round(voluntary / ticks, 3),
        "involuntary_switches_per_device_tick": round(involuntary / ticks, 3),
        "missed_deadlines": sum(d["missed_deadlines"] for d in r["devices"]),
        "late_wakeups": sum(d["late_wakeups"] for d in r["devices"]),
        "stable_devices": sum(1 for d in r["devices"] if d["stable"]),
        "stable": r["total"]["stable"],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("hapto")
    ap.add_argument("--counts", default="1,8,32,64,128")
    ap.add_argument("--per-thread", default="1")
    ap.add_argument("--duration", type=float, default=12.0)
    ap.add_argument("--rate", type=float, default=1000.0)
    ap.add_argument("--warm-us", default="default",
                    help="servo warm-ups to run, us; 'default' passes none (the runtime's)")
    ap.add_argument("--json")
    a = ap.parse_args()
    try:
        warms = [None if w == "default" else float(w) for w in a.warm_us.split(",")]
    except ValueError:
        warms = []
    if not warms or any(w is not None and not (0 <= w < float("inf")) for w in warms):
        print(f"--warm-us: expected a comma-separated list of finite numbers >= 0 (us) or "
              f"'default', got '{a.warm_us}'", file=sys.stderr)
        sys.exit(2)
    if not (WARMUP_S + 3 <= a.duration < float("inf")):
        print(f"--duration: at least {WARMUP_S + 3} s ({WARMUP_S} s of start-up and 1 s at the "
              f"end are left out), got {a.duration}", file=sys.stderr)
        sys.exit(2)
    if not (0 < a.rate < float("inf")):
        print(f"--rate: expected a finite rate > 0 (Hz), got {a.rate}", file=sys.stderr)
        sys.exit(2)
    try:
        counts = [int(c) for c in a.counts.split(",")]
        per_threads = [int(k) for k in a.per_thread.split(",")]
    except ValueError:
        counts = per_threads = []
    if not counts or not per_threads or min(counts + per_threads) < 1:
        print(f"--counts / --per-thread: expected comma-separated integers >= 1, got "
              f"'{a.counts}' / '{a.per_thread}'", file=sys.stderr)
        sys.exit(2)
    rows = []
    with tempfile.TemporaryDirectory() as scratch:
        print(f"{'N':>4} {'K':>3} {'warm':>5} {'thr':>4} {'cpu/tick':>8} {'servo':>6} {'tick':>6} "
              f"{'share':>6} {'servo':>6} {'other':>6} {'vol/tk':>6} {'inv/tk':>6} "
              f"{'missed':>7} {'stable':>7}   (us per device-tick; shares of all cores)")
        for count, per_thread, warm in itertools.product(counts, per_threads, warms):
            w = run_one(a.hapto, count, per_thread, warm, a.duration, a.rate, scratch)
            rows.append(w)
            warm_text = "dflt" if warm is None else f"{warm:g}"
            print(f"{count:>4} {per_thread:>3} {warm_text:>5} {w['servo_threads']:>4} "
                  f"{w['cpu_per_device_tick_us']:>8.2f} "
                  f"{w['servo_cpu_per_device_tick_us']:>6.2f} {w['tick_itself_us']:>6.2f} "
                  f"{100 * w['process_share_of_cores']:>5.1f}% "
                  f"{100 * w['servo_share_of_cores']:>5.1f}% "
                  f"{100 * w['other_threads_cpu_share']:>5.1f}% "
                  f"{w['voluntary_switches_per_device_tick']:>6.3f} "
                  f"{w['involuntary_switches_per_device_tick']:>6.3f} "
                  f"{w['missed_deadlines']:>7} {w['stable_devices']:>3}/{count:<3}",
                  flush=True)
    if a.json:
        # Written beside the target and renamed into place: a run that fails loses nothing.
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump({"cores": os.cpu_count(), "rate_hz": a.rate, "runs": rows}, f, indent=1)
        os.replace(tmp, a.json)


if __name__ == "__main__":
    main()
