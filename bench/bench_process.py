#!/usr/bin/python3
"""The whole simulate_pass process against its pass, and the fast rung against the accurate one.

  bench/bench_process.py [--reps 7] [--scene config/reference_55m.yaml] [--speed 300]
                         [--presets fast,accurate] [--base OTHER/simulate_pass] [--changed fast]

For each preset, simulate_pass --scene SCENE --speed SPEED --set numerics.preset=P --out TMP runs
--reps times; each run gives
  process: the wall time of the whole process (start to exit, timed here),
  pass:    stats.json's wall_time_s (the stepping of the pass alone),
  build:   stats.json's build_time_s (scene, model, statics, initial state);
and the rest of the process (start-up, statistics, writing the files) is process - pass - build.
Printed per preset: the medians and minima, process / pass (the overhead a study pays each case),
and accurate / fast per simulated second of pass and of process (the ladder's ratio).

With --base, a second simulate_pass (e.g. a build of an older commit) alternates run by run with
this one in the same loop, and the ratios base / this are printed: the machine's load moves both
alike. The two binaries' files of each preset are compared after the first run: byte for byte,
stats.json without its timings (wall_time_s, build_time_s, real_time_factor); a difference is
printed and the exit status is 1, but for the presets given with --changed, whose numerics differ
from the base's on purpose (their differences are printed). Uses Debian's /usr/bin/python3. Build first: SKIP_SETUP=1
scripts/build.
"""
import argparse
import filecmp
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
LIB = os.path.join(ROOT, ".ws", "devel", "lib", "catenary_sim")


def run_once(binary, scene, speed, preset, out):
    args = [binary, "--scene", scene, "--speed", str(speed), "--set", f"numerics.preset={preset}", "--out", out,
            "--quiet", "--no-progress"]
    start = time.perf_counter()
    r = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
    process = time.perf_counter() - start
    if r.returncode != 0:
        sys.exit(f"{' '.join(args)} failed ({r.returncode}):\n{r.stdout[-2000:]}")
    with open(os.path.join(out, "stats.json")) as f:
        s = json.load(f)
    return {"process": process, "pass": s["wall_time_s"], "build": s["build_time_s"],
            "simulated": s["simulated_time_s"]}


TIMINGS = ("wall_time_s", "build_time_s", "real_time_factor")


def differing_files(a, b):
    """The names of the files in directory a or b that differ (stats.json: all but its timings)."""
    names = sorted(set(os.listdir(a)) | set(os.listdir(b)))
    out = []
    for n in names:
        pa, pb = os.path.join(a, n), os.path.join(b, n)
        if not (os.path.isfile(pa) and os.path.isfile(pb)):
            out.append(n)
        elif n == "stats.json":
            with open(pa) as fa, open(pb) as fb:
                ja, jb = json.load(fa), json.load(fb)
            if {k: v for k, v in ja.items() if k not in TIMINGS} != {k: v for k, v in jb.items() if k not in TIMINGS}:
                out.append(n)
        elif not filecmp.cmp(pa, pb, shallow=False):
            out.append(n)
    return out


def summary(runs):
    keys = ("process", "pass", "build")
    med = {k: statistics.median(r[k] for r in runs) for k in keys}
    low = {k: min(r[k] for r in runs) for k in keys}
    med["rest"] = statistics.median(r["process"] - r["pass"] - r["build"] for r in runs)
    med["simulated"] = runs[0]["simulated"]
    return med, low


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--reps", type=int, default=7, help="runs per preset and binary (default 7)")
    p.add_argument("--scene", default=os.path.join(ROOT, "config", "reference_55m.yaml"))
    p.add_argument("--speed", type=float, default=300.0, help="km/h (default 300)")
    p.add_argument("--presets", default="fast,accurate", help="comma-separated (default fast,accurate)")
    p.add_argument("--base", help="another simulate_pass to alternate with, for base / this ratios")
    p.add_argument("--changed", default="", help="comma-separated presets whose numerics differ from the base's "
                   "on purpose: their files' differences are printed, not failed on")
    a = p.parse_args()
    if a.reps < 1:
        p.error(f"--reps {a.reps}: allowed 1 or more")
    presets = [x for x in a.presets.split(",") if x]
    changed = [x for x in a.changed.split(",") if x]
    for pr in changed:
        if pr not in presets:
            p.error(f"--changed {pr}: not one of --presets {a.presets}")
    binaries = {"this": os.path.join(LIB, "simulate_pass")}
    if a.base:
        binaries["base"] = a.base
    for name, b in binaries.items():
        if not os.access(b, os.X_OK):
            p.error(f"{name} simulate_pass {b}: not an executable (build first: SKIP_SETUP=1 scripts/build)")
    runs = {(b, pr): [] for b in binaries for pr in presets}
    differ = {}
    with tempfile.TemporaryDirectory(prefix="catenary_sim_bench_process_") as tmp:
        for rep in range(a.reps):
            for pr in presets:
                for b, path in binaries.items():
                    runs[(b, pr)].append(run_once(path, a.scene, a.speed, pr, os.path.join(tmp, f"{b}_{pr}")))
                if rep == 0 and a.base:
                    differ[pr] = differing_files(os.path.join(tmp, f"this_{pr}"), os.path.join(tmp, f"base_{pr}"))
            print(f"rep {rep + 1}/{a.reps} done", file=sys.stderr, flush=True)
    res = {k: summary(v) for k, v in runs.items()}
    print(f"scene {os.path.relpath(a.scene, ROOT)}, {a.speed:g} km/h, {a.reps} runs each; times in s (median; min)")
    print("| binary | preset | process | pass | build | rest | process / pass |")
    print("|---|---|---|---|---|---|---|")
    for (b, pr), (med, low) in res.items():
        print(f"| {b} | {pr} | {med['process']:.4f}; {low['process']:.4f} | {med['pass']:.4f}; {low['pass']:.4f} | "
              f"{med['build']:.4f} | {med['rest']:.4f} | {med['process'] / med['pass']:.2f} |")
    if "fast" in presets and "accurate" in presets:
        for b in binaries:
            f, acc = res[(b, "fast")][0], res[(b, "accurate")][0]
            per_s = lambda m, k: m[k] / m["simulated"]  # noqa: E731
            print(f"{b}: accurate / fast per simulated second: pass {per_s(acc, 'pass') / per_s(f, 'pass'):.2f}, "
                  f"process {per_s(acc, 'process') / per_s(f, 'process'):.2f}")
    if a.base:
        for pr in presets:
            mb, mt = res[("base", pr)][0], res[("this", pr)][0]
            print(f"{pr}: base / this: process {mb['process'] / mt['process']:.2f}, pass {mb['pass'] / mt['pass']:.2f}, "
                  f"build {mb['build'] / mt['build']:.2f}")
        for pr, names in differ.items():
            print(f"{pr}: files of this and base: " + ("the same (stats.json but its timings)" if not names
                                                         else "DIFFERENT: " + ", ".join(names))
                  + (" (numerics changed on purpose)" if pr in changed else ""))
        if any(names for pr, names in differ.items() if pr not in changed):
            sys.exit(1)


if __name__ == "__main__":
    main()
