#!/usr/bin/python3
"""Throughput of a study on Dask with 1 and 2 local workers, and its overhead per case against a
bare simulate_pass of the same case (the study harness's overhead).

  bench/bench_study_scale.py [--cases 24] [--spans 30] [--reps 2]

The study: --cases passes of the reference line lengthened to --spans spans at 300 km/h, each
with its own random dropper-length errors (imperfections.seed varied over a grid), so every case
costs the same and none is a copy of another. Measured in one run, alternating:
(a) catenary_sim_study with --workers 1 and with --workers 2 (fresh output directories, no plots),
    wall time of the whole command; throughput = cases / (wall - the time to start Python and a
    ready cluster of that many workers, measured alone): the start-up is paid once per study.
    Target: 2 workers >= 1.8 x 1 worker. The whole commands' ratio is printed too.
(b) simulate_pass --scene SCENE --set ... --out TMP for the same cases one after another (each its
    own process, as a shell loop would run them), wall time of each command. Overhead per case =
    (study wall with 1 worker) / (sum of the bare passes' walls) - 1. Target: <= 10 %.
    The study's wall includes starting its Dask cluster (measured alone, reported beside it).
Medians over --reps repetitions. Compare on a quiet machine: other load takes the second core.
Build first: SKIP_SETUP=1 scripts/build; uses /usr/bin/python3 and the workspace's module.
"""
import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
LIB = os.path.join(ROOT, ".ws", "devel", "lib", "catenary_sim")
SCENE = os.path.join(ROOT, "config", "reference_55m.yaml")
TARGETS = {"speedup_min": 1.8, "overhead_max": 0.10}


def env():
    e = dict(os.environ)
    e["PATH"] = "/usr/bin:" + e.get("PATH", "")
    py = os.path.join(ROOT, ".ws", "devel", "lib", "python3", "dist-packages")
    e["PYTHONPATH"] = py + os.pathsep + os.path.join(ROOT, "python") + os.pathsep + e.get("PYTHONPATH", "")
    e["CATENARY_SIM_DEVEL_LIB"] = LIB
    return e


def timed(cmd):
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, env=env(), stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT, timeout=3600)
    return time.perf_counter() - t0


def cluster_startup(workers):
    """Seconds from starting Python to a ready local cluster of `workers` processes (the fixed cost
    every study command pays before its first case, whatever its size)."""
    code = ("import time; t=time.perf_counter()\n"
            "from dask.distributed import Client, LocalCluster\n"
            f"c=LocalCluster(n_workers={workers}, threads_per_worker=1, processes=True, dashboard_address=None); cl=Client(c)\n"
            "cl.wait_for_workers(%d); print(time.perf_counter()-t); cl.close(); c.close()" % workers)
    out = subprocess.run(["/usr/bin/python3", "-c", code], check=True, env=env(), capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=24)
    ap.add_argument("--spans", type=int, default=30)
    ap.add_argument("--reps", type=int, default=2)
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="bench_study_")
    try:
        overrides = {"line.span_count": a.spans, "train.speed_kmh": 300, "imperfections.dropper_length_std": 0.003}
        study = {"name": "bench_scale", "scene": SCENE, "overrides": overrides, "sampling": "grid",
                 "parameters": [{"key": "imperfections.seed", "values": list(range(1, a.cases + 1))}],
                 "outputs": ["pantographs.0.std_force_N"]}
        spec = os.path.join(tmp, "study.yaml")
        with open(spec, "w") as f:
            yaml.safe_dump(study, f)
        sets = [f"--set={k}={v}" for k, v in overrides.items()]
        walls = {1: [], 2: []}
        bare = []
        for rep in range(a.reps):
            for w in (1, 2):
                out = os.path.join(tmp, f"out_{w}_{rep}")
                walls[w].append(timed(["/usr/bin/python3", os.path.join(ROOT, "scripts", "catenary_sim_study"), spec,
                                       "--out", out, "--workers", str(w), "--no-progress", "--no-plots"]))
                print(f"rep {rep}: {w} worker(s) {walls[w][-1]:.1f} s", flush=True)
            total = 0.0
            for seed in range(1, a.cases + 1):
                total += timed([os.path.join(LIB, "simulate_pass"), "--scene", SCENE, *sets,
                                f"--set=imperfections.seed={seed}", "--out", os.path.join(tmp, "bare")])
            bare.append(total)
            print(f"rep {rep}: bare simulate_pass x {a.cases} {total:.1f} s", flush=True)
        startup = {w: statistics.median(cluster_startup(w) for _ in range(3)) for w in (1, 2)}
        w1, w2, b = statistics.median(walls[1]), statistics.median(walls[2]), statistics.median(bare)
        # Throughput is cases per second once the cluster runs: the start-up (Python, Dask, the
        # workers' processes) is paid once per study, however many cases it has, so it is taken
        # out; the whole commands' ratio is printed beside it.
        speedup = (w1 - startup[1]) / (w2 - startup[2])
        overhead = w1 / b - 1.0
        print()
        print(f"cases {a.cases} (reference line, {a.spans} spans, 300 km/h, one pass {b / a.cases:.2f} s), "
              f"medians of {a.reps}, {os.cpu_count()} CPUs")
        print(f"  1 worker : {w1:.1f} s  ({a.cases / w1:.2f} cases/s)")
        print(f"  2 workers: {w2:.1f} s  ({a.cases / w2:.2f} cases/s), whole commands x {w1 / w2:.2f}")
        print(f"  starting the cluster: {startup[1]:.1f} s (1 worker), {startup[2]:.1f} s (2 workers)")
        print(f"  throughput once running: 1 worker {a.cases / (w1 - startup[1]):.2f} cases/s, 2 workers "
              f"{a.cases / (w2 - startup[2]):.2f} cases/s: x {speedup:.2f} (target >= {TARGETS['speedup_min']})")
        print(f"  bare simulate_pass, one after another: {b:.1f} s")
        print(f"  overhead per case with 1 worker: {100 * overhead:.1f} % (target <= {100 * TARGETS['overhead_max']:.0f} %), "
              f"of which starting the Dask cluster {startup[1]:.1f} s = {100 * startup[1] / b:.1f} %")
        ok = speedup >= TARGETS["speedup_min"] and overhead <= TARGETS["overhead_max"]
        print("targets met" if ok else "targets NOT met")
        return 0 if ok else 1
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
