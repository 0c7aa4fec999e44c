#!/usr/bin/python3
"""Each kind of line's cost per DOF and step against the simple line's.

  bench/bench_line_kinds.py [--reps 7] [--preset accurate]
                            [--scenes config/reference_55m.yaml,config/reference_55m_stitched.yaml,...]

A scene may carry --set overrides after '@', one per '@' (values without commas):
config/rigid_conductor_rail_3d.yaml@wind.speed=30 is the 3-D rail in a 30 m/s cross wind.

simulate_pass runs each scene in turn, --reps rounds, the scenes alternating within each round so
that the machine's load moves them alike. Each run gives stats.json's wall_time_s (the stepping of
the pass alone), dofs and steps; the cost is wall_time_s / (dofs x steps) in ns. Printed per scene:
the median and minimum cost, its dt, DOFs and steps, and the median's and the minimum's ratios to
the first scene's (the simple line). Uses Debian's /usr/bin/python3. Build first: SKIP_SETUP=1 scripts/build.

  bench/bench_line_kinds.py --against OTHER/simulate_pass [--reps 9] [--scenes ...]

compares two builds instead: each scene runs on this tree's simulate_pass and on OTHER's (e.g. a
`git worktree` of another commit, built there), the two alternated within each round and their
order swapped every round; printed per scene: both medians and minima, and this build's over the
other's.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
SIMULATE_PASS = os.path.join(ROOT, ".ws", "devel", "lib", "catenary_sim", "simulate_pass")
DEFAULT_SCENES = ["config/reference_55m.yaml", "config/reference_55m_stitched.yaml", "config/reference_55m_hinged_arms.yaml",
                  "config/rigid_conductor_rail.yaml", "config/compound_catenary.yaml", "config/trolley_wire.yaml"]


def split_entry(entry):
    """'file@field=value@...' into the file and its --set overrides."""
    path, *overrides = entry.split("@")
    return path, overrides


def run_once(entry, preset, out, program=SIMULATE_PASS):
    scene, overrides = split_entry(entry)
    args = [program, "--scene", scene, "--set", f"numerics.preset={preset}", "--out", out, "--quiet",
            "--no-progress"]
    for o in overrides:
        args += ["--set", o]
    r = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600, cwd=ROOT)
    if r.returncode != 0:
        sys.exit(f"{' '.join(args)} failed ({r.returncode}):\n{r.stdout[-2000:]}")
    with open(os.path.join(out, "stats.json")) as f:
        return json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=7, help="rounds over the scenes (1-1000)")
    ap.add_argument("--preset", default="accurate", choices=["fast", "balanced", "accurate", "reference"])
    ap.add_argument("--scenes", default=",".join(DEFAULT_SCENES),
                    help="comma-separated scene files, each with --set overrides after '@' (file@field=value); "
                         "the first is the one the others are compared with")
    ap.add_argument("--against", metavar="SIMULATE_PASS",
                    help="another build's simulate_pass: each scene on both builds, alternated")
    a = ap.parse_args()
    if not 1 <= a.reps <= 1000:
        ap.error(f"--reps {a.reps}: allowed 1-1000")
    if a.against is not None and not (os.path.isfile(a.against) and os.access(a.against, os.X_OK)):
        ap.error(f"--against {a.against}: not an executable file; allowed another build's simulate_pass")
    scenes = [s for s in a.scenes.split(",") if s]
    for s in scenes:
        path, overrides = split_entry(s)
        if not os.path.isfile(os.path.join(ROOT, path)):
            ap.error(f"--scenes: no file '{path}' (paths relative to the repository)")
        for o in overrides:
            if "=" not in o:
                ap.error(f"--scenes: override '{o}' of '{path}' is not field=value")
    if not os.access(SIMULATE_PASS, os.X_OK):
        sys.exit(f"no {SIMULATE_PASS}: build first (SKIP_SETUP=1 scripts/build)")
    if a.against is not None:
        compare_builds(scenes, a.reps, a.preset, os.path.abspath(a.against))
        return
    cost = {s: [] for s in scenes}
    last = {}
    with tempfile.TemporaryDirectory(prefix="bench_line_kinds_") as tmp:
        for _ in range(a.reps):
            for i, s in enumerate(scenes):
                st = run_once(s, a.preset, os.path.join(tmp, str(i)))
                cost[s].append(st["wall_time_s"] / (st["dofs"] * st["steps"]) * 1e9)
                last[s] = st
    base, base_min = statistics.median(cost[scenes[0]]), min(cost[scenes[0]])
    print(f"preset {a.preset}, {a.reps} rounds; cost = pass wall / (DOFs x steps)")
    width = max(40, *(len(s) for s in scenes))
    print(f"{'scene':{width}s} {'DOFs':>6s} {'steps':>6s} {'dt (ms)':>8s} {'median ns':>10s} {'min ns':>8s} {'/ first':>8s} "
          f"{'min / first min':>15s}")
    for s in scenes:
        med = statistics.median(cost[s])
        st = last[s]
        print(f"{s:{width}s} {st['dofs']:6d} {st['steps']:6d} {st['dt_s'] * 1e3:8.4f} {med:10.3f} {min(cost[s]):8.3f} "
              f"{med / base:8.3f} {min(cost[s]) / base_min:15.3f}")


def compare_builds(scenes, reps, preset, other):
    """Each scene on this tree's build and on `other`, alternated, the order swapped each round."""
    builds = [("this", SIMULATE_PASS), ("other", other)]
    cost = {(b, s): [] for b, _ in builds for s in scenes}
    with tempfile.TemporaryDirectory(prefix="bench_line_kinds_") as tmp:
        for r in range(reps):
            for i, s in enumerate(scenes):
                for b, program in (builds if r % 2 == 0 else builds[::-1]):
                    st = run_once(s, preset, os.path.join(tmp, str(i)), program)
                    cost[(b, s)].append(st["wall_time_s"] / (st["dofs"] * st["steps"]) * 1e9)
    print(f"preset {preset}, {reps} rounds; cost = pass wall / (DOFs x steps); this build: {SIMULATE_PASS}, "
          f"other: {other}")
    width = max(40, *(len(s) for s in scenes))
    print(f"{'scene':{width}s} {'this median':>11s} {'this min':>9s} {'other median':>12s} {'other min':>9s} "
          f"{'median ratio':>12s} {'min ratio':>9s}")
    for s in scenes:
        t, o = cost[("this", s)], cost[("other", s)]
        print(f"{s:{width}s} {statistics.median(t):11.3f} {min(t):9.3f} {statistics.median(o):12.3f} {min(o):9.3f} "
              f"{statistics.median(t) / statistics.median(o):12.3f} {min(t) / min(o):9.3f}")


if __name__ == "__main__":
    main()
