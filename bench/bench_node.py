#!/usr/bin/python3
"""Times the live node against the offline runner on the reference pass (the pacing overhead).

  bench/bench_node.py [--reps 3] [--rt-runs 1] [--speed 300] [--scene config/reference_55m.yaml]

(a) simulate_pass --scene SCENE --speed 300 --out TMP: wall_time_s and real_time_factor from its
    stats.json (the pass only: model building and statistics are not in wall_time_s);
(b) catenary_sim_node _real_time_factor:=0 _at_end:=exit _stats_file:=...: the same from its
    stats file (wall from the first tick to the end of the pass, publishing included);
    (a) and (b) alternate --reps times, the medians are compared as a ratio (the target), and the
    minima too (load only adds time, so that ratio is steadier on a busy machine);
(c) the node at _real_time_factor:=1.0, --rt-runs times: chunks (ticks that stepped) and
    overruns from its end-of-pass log line, achieved real-time factor from its stats file.

The node runs against a private roscore on a free loopback port (ROS_MASTER_URI and ROS_HOSTNAME
localhost, ROS_HOME in a temporary directory); nothing subscribes to its topics. Every process has
a time limit and everything started here is stopped on exit (also on Ctrl-C or a failure).
Uses Debian's /usr/bin/python3 and ROS (a pyenv python3 on PATH lacks the ROS modules).
Build first: SKIP_SETUP=1 scripts/build.
"""
import argparse
import atexit
import json
import os
import re
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import xmlrpc.client

ROOT = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
WS = os.path.join(ROOT, ".ws")
LIB = os.path.join(WS, "devel", "lib", "catenary_sim")
TARGETS = {"rtf0_ratio_max": 1.10, "overrun_share_max": 0.01}

_started = []  # Popen objects of long-lived processes (roscore), stopped at exit
_tmp = None


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def descendants(pid):
    """Pids of every process below pid (from /proc), deepest last."""
    children = {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(d))
    out, todo = [], [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out.append(c)
            todo.append(c)
    return out


def alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def stop(proc, grace=10.0):
    """SIGINT a process we started (roscore shuts its children down), then SIGKILL what is left."""
    if proc.poll() is not None:
        return
    below = descendants(proc.pid)  # rosmaster and rosout run in sessions of their own
    try:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=5)
    deadline = time.monotonic() + 5.0
    while any(alive(p) for p in below) and time.monotonic() < deadline:
        time.sleep(0.1)
    for p in below:
        if alive(p):
            try:
                os.kill(p, signal.SIGKILL)
            except OSError:
                pass


def cleanup():
    while _started:
        stop(_started.pop())
    if _tmp and os.environ.get("BENCH_KEEP_TMP") != "1":
        shutil.rmtree(_tmp, ignore_errors=True)


def on_signal(signum, _frame):
    cleanup()
    sys.exit(128 + signum)


def ros_env(tmp, port):
    """The devel space's environment with /usr/bin first and a private loopback master."""
    base = dict(os.environ)
    base["PATH"] = "/usr/bin:/bin:" + base.get("PATH", "")
    for k in ("ROS_PACKAGE_PATH", "CMAKE_PREFIX_PATH", "ROS_IP", "PYTHONPATH", "PYENV_VERSION"):
        base.pop(k, None)
    out = subprocess.run(["bash", "-c", f"source '{WS}/devel/setup.bash' && env -0"], env=base,
                         stdout=subprocess.PIPE, check=True, timeout=60).stdout
    env = dict(kv.split("=", 1) for kv in out.decode().split("\0") if "=" in kv)
    env.update(ROS_MASTER_URI=f"http://localhost:{port}", ROS_HOSTNAME="localhost",
               ROS_HOME=os.path.join(tmp, "ros_home"))
    return env


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_roscore(env, port, tmp, timeout=30.0):
    logf = open(os.path.join(tmp, "roscore.log"), "w")
    proc = subprocess.Popen(["/usr/bin/roscore", "-p", str(port)], env=env, stdout=logf,
                            stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)
    _started.append(proc)
    master = xmlrpc.client.ServerProxy(f"http://localhost:{port}")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"roscore exited ({proc.returncode}); see {logf.name}")
        try:
            code, _, state = master.getSystemState("/bench_node")
            # wait for /rosout too, so that it does not start during a timed run
            if code == 1 and any(t == "/rosout_agg" for t, _ in state[0]):
                return proc
        except (OSError, xmlrpc.client.Error):
            pass
        time.sleep(0.2)
    raise RuntimeError(f"roscore on port {port} not up within {timeout:.0f} s")


def private_roscore(prefix):
    """A roscore on a free loopback port, its logs in a new temporary directory, stopped (with
    every process started here) at exit or on a signal. Returns the environment to run nodes in."""
    global _tmp
    atexit.register(cleanup)
    for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(s, on_signal)
    _tmp = tempfile.mkdtemp(prefix=prefix)
    port = free_port()
    env = ros_env(_tmp, port)
    start_roscore(env, port, _tmp)
    log(f"roscore on localhost:{port}, logs in {_tmp}")
    return env


def stop_processes(procs, logs=()):
    """Stops `procs` in their order (SIGINT, then kill after 20 s) and closes `logs`."""
    for p in procs:
        if p.poll() is None:
            p.send_signal(signal.SIGINT)
        try:
            p.wait(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(timeout=5)
        if p in _started:
            _started.remove(p)
    for log in logs:
        log.close()


def run(cmd, env, timeout, logname):
    with open(logname, "w") as f:
        try:
            p = subprocess.run(cmd, env=env, stdout=f, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                               timeout=timeout, start_new_session=True)
        except subprocess.TimeoutExpired:  # subprocess.run kills the child
            raise RuntimeError(f"{os.path.basename(cmd[0])} took more than {timeout:.0f} s; see {logname}")
    if p.returncode != 0:
        raise RuntimeError(f"{os.path.basename(cmd[0])} exited with {p.returncode}; see {logname}")
    with open(logname) as f:
        return f.read()


def offline(args, env, tmp, i):
    out = os.path.join(tmp, f"offline{i}")
    run([os.path.join(LIB, "simulate_pass"), "--scene", args.scene, "--speed", str(args.speed), "--out", out,
         "--quiet"], env, 120, out + ".log")
    with open(os.path.join(out, "stats.json")) as f:
        return json.load(f)


def node(args, env, tmp, label, rtf, timeout):
    stats_file = os.path.join(tmp, f"node_{label}.json")
    text = run([os.path.join(LIB, "catenary_sim_node"), f"__name:=catenary_sim_{label}",
                f"_scene:={args.scene}", f"_speed_kmh:={float(args.speed)}", f"_real_time_factor:={float(rtf)}",
                "_at_end:=exit", f"_stats_file:={stats_file}"], env, timeout, os.path.join(tmp, f"node_{label}.log"))
    with open(stats_file) as f:
        s = json.load(f)
    m = re.search(r"pass finished at .*?(\d+) chunks, (\d+) overruns", text)
    s["chunks"] = int(m.group(1)) if m else None
    if m:
        s["overruns_logged"] = int(m.group(2))
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default=os.path.join(ROOT, "config", "reference_55m.yaml"))
    ap.add_argument("--speed", type=float, default=300.0, help="km/h")
    ap.add_argument("--reps", type=int, default=3, help="alternating offline / node rtf 0 pairs")
    ap.add_argument("--rt-runs", type=int, default=1, help="node runs at real_time_factor 1.0")
    args = ap.parse_args()
    if args.reps < 1 or args.rt_runs < 0:
        ap.error("--reps must be at least 1 and --rt-runs at least 0")
    args.scene = os.path.realpath(args.scene)
    for exe in ("simulate_pass", "catenary_sim_node"):
        if not os.access(os.path.join(LIB, exe), os.X_OK):
            sys.exit(f"bench_node: {LIB}/{exe} missing: run SKIP_SETUP=1 scripts/build first")

    env = private_roscore("bench_node_")

    off, fast = [], []
    for i in range(args.reps):
        off.append(offline(args, env, _tmp, i))
        fast.append(node(args, env, _tmp, f"rtf0_{i}", 0.0, 120))
        log(f"pair {i + 1}/{args.reps}: offline {off[-1]['wall_time_s']:.4f} s, node rtf 0 {fast[-1]['wall_time_s']:.4f} s")
    sim_t = off[0]["simulated_time_s"]
    rt = []
    for i in range(args.rt_runs):
        rt.append(node(args, env, _tmp, f"rtf1_{i}", 1.0, 3.0 * sim_t + 60))
        log(f"rtf 1 run {i + 1}/{args.rt_runs}: {rt[-1]['chunks']} chunks, {rt[-1]['overruns']} overruns")

    off_med = statistics.median(s["wall_time_s"] for s in off)
    fast_med = statistics.median(s["wall_time_s"] for s in fast)
    ratio = fast_med / off_med
    # Load on the machine only ever adds time: the ratio of the fastest runs is the steadier figure.
    ratio_min = min(s["wall_time_s"] for s in fast) / min(s["wall_time_s"] for s in off)

    print(f"scene {os.path.relpath(args.scene, ROOT)}, {args.speed:g} km/h: {off[0]['dofs']} DOFs, "
          f"dt {off[0]['dt_s'] * 1e3:.4f} ms, {off[0]['steps']} steps, {sim_t:.4f} s simulated")
    print()
    print("| run | wall per run (s) | wall, median (s) | wall, min (s) | real-time factor (median) | chunks | overruns |")
    print("|---|---|---|---|---|---|---|")
    walls = lambda runs: " / ".join(f"{s['wall_time_s']:.4f}" for s in runs)
    wmin = lambda runs: min(s["wall_time_s"] for s in runs)
    print(f"| offline simulate_pass | {walls(off)} | {off_med:.4f} | {wmin(off):.4f} | {sim_t / off_med:.1f} | - | - |")
    print(f"| node, real_time_factor 0 | {walls(fast)} | {fast_med:.4f} | {wmin(fast):.4f} | {sim_t / fast_med:.1f} | "
          f"{' / '.join(str(s['chunks']) for s in fast)} | {' / '.join(str(s['overruns']) for s in fast)} |")
    for s in rt:
        share = s["overruns"] / s["chunks"] if s["chunks"] else float("nan")
        print(f"| node, real_time_factor 1.0 | {s['wall_time_s']:.4f} | - | - | {s['real_time_factor']:.4f} | "
              f"{s['chunks']} | {s['overruns']} ({100 * share:.2f} %) |")
    print()
    ok0 = ratio <= TARGETS["rtf0_ratio_max"]
    print(f"node rtf 0 / offline, medians of {args.reps}: {ratio:.3f} "
          f"(target <= {TARGETS['rtf0_ratio_max']:.2f}: {'met' if ok0 else 'NOT met'}); "
          f"fastest runs: {ratio_min:.3f}")
    ok1 = True
    for s in rt:
        share = s["overruns"] / s["chunks"] if s["chunks"] else float("nan")
        ok = share < TARGETS["overrun_share_max"] and s["real_time_factor"] >= 0.99
        ok1 = ok1 and ok
        print(f"node rtf 1.0: achieved {s['real_time_factor']:.4f}, overruns {s['overruns']}/{s['chunks']} chunks = "
              f"{100 * share:.2f} % (target < 1 % and real time held: {'met' if ok else 'NOT met'})")
    return 0 if ok0 and ok1 else 1


if __name__ == "__main__":
    sys.exit(main())
