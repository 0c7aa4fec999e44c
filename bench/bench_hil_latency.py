#!/usr/bin/python3
"""Latency of the hardware-in-the-loop node (the loop on the wall clock).

  bench/bench_hil_latency.py [--rates 1000,2000,5000] [--durations 600,60,60] [--chrt 0]

For each rate: catenary_sim_hil_node on config/reference_55m_hil.yaml (300 km/h, _at_end:=loop:
the pass is repeated, 6.6 s each) and virtual_rig (the reference lumped pantograph, paced at the
same rate on its own clock) close the loop over hil/contact_force and hil/contact_point for the
given wall-clock duration; then both get SIGINT and write their reports:

  latency    measurement arrival (the node's callback) -> the contact point computed with it
             published (the node's ~hil/report_file): p50, p99, p99.9, max
  compute    start of a period's steps -> its contact point published (every period)
  overruns   periods whose window closed before the loop got to them (the loop fell behind)
  held       periods without a fresh measurement in their window (the held one was used)
  round trip the rig's view: measurement sent -> the contact point that used it received
             (two transports and the node; virtual_rig's ~report_file)

Targets (at 1 kHz): latency p99 < 0.5 ms and no overruns; the script exits with status 1 if
missed. --chrt N runs both processes under `chrt -f N` (SCHED_FIFO, needs the right to).
--inprocess runs both as nodelets (catenary_sim/HilNodelet, catenary_sim/VirtualRigNodelet) in
one nodelet manager: the messages pass as shared pointers, no serialisation, no socket.
--spin-wait S sets the node's ~hil/spin_wait. --watch-outputs subscribes to pantograph_state and
wire_shape (rostopic hz) during the run: what publishing them costs the loop.

Runs against a private roscore on a free loopback port (reusing bench_node.py's helpers);
everything started here is stopped on exit. Build first: SKIP_SETUP=1 scripts/build
(CATENARY_SIM_WS=DIR: a catkin workspace other than .ws/).
"""
import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import bench_node as bn  # noqa: E402  (roscore, environment and process helpers)

ROOT = bn.ROOT
if os.environ.get("CATENARY_SIM_WS"):  # another catkin workspace than .ws/
    bn.WS = os.path.realpath(os.environ["CATENARY_SIM_WS"])
    bn.LIB = os.path.join(bn.WS, "devel", "lib", "catenary_sim")
LIB = bn.LIB
TARGETS = {"p99_max_s": 0.5e-3, "overruns": 0}


def loadavg():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


NODELET = "/usr/lib/nodelet/nodelet"  # Debian's libnodeletlib-tools (rosrun nodelet nodelet)


def run_rate(rate, duration, env, tmp, chrt, spin_wait, inprocess, watch):
    label = f"{int(rate)}hz"
    node_report = os.path.join(tmp, f"node_{label}.json")
    rig_report = os.path.join(tmp, f"rig_{label}.json")
    prefix = ["chrt", "-f", str(chrt)] if chrt > 0 else []
    manager = f"hil_manager_{label}"
    # In-process: a nodelet manager, and the node and the rig loaded into it by two loader processes
    # (named as the node and the rig, whose private parameters they carry).
    node_exe = [NODELET, "load", "catenary_sim/HilNodelet", manager] if inprocess else \
        [os.path.join(LIB, "catenary_sim_hil_node")]
    rig_exe = [NODELET, "load", "catenary_sim/VirtualRigNodelet", manager] if inprocess else \
        [os.path.join(LIB, "virtual_rig")]
    node_cmd = node_exe + [f"__name:=hil_{label}",
                           f"_scene:={os.path.join(ROOT, 'config', 'reference_55m_hil.yaml')}",
                           f"_hil/rate:={float(rate)}", "_hil/timeout:=0.05", "_at_end:=loop",
                           f"_hil/report_file:={node_report}"]
    if spin_wait is not None:
        node_cmd.append(f"_hil/spin_wait:={float(spin_wait)}")
    rig_cmd = rig_exe + [f"__name:=rig_{label}",
                         f"_pantograph_scene:={os.path.join(ROOT, 'config', 'reference_55m.yaml')}",
                         f"_report_file:={rig_report}"]
    if inprocess:  # the manager first, at the priority asked for; the loaders are plain clients
        cmds = [prefix + [NODELET, "manager", f"__name:={manager}"], node_cmd, rig_cmd]
        names = ("manager", "node", "rig")
    else:
        cmds = [prefix + node_cmd, prefix + rig_cmd]
        names = ("node", "rig")
    if watch:  # a subscriber to the decimated outputs (its own CPU time is part of the load)
        cmds.append(["/usr/bin/rostopic", "hz", "pantograph_state", "wire_shape"])
        names += ("watch",)
    logs = [open(os.path.join(tmp, f"{n}_{label}.log"), "w") for n in names]
    procs = []
    load0 = loadavg()
    try:
        for cmd, log in zip(cmds, logs):
            p = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                 start_new_session=True)
            bn._started.append(p)
            procs.append(p)
        deadline = time.monotonic() + duration + 5.0  # (+ start-up: the model is built first)
        while time.monotonic() < deadline:
            for p in procs:
                if p.poll() is not None:
                    raise RuntimeError(f"{' '.join(p.args[:4])} exited with {p.returncode}; "
                                       f"see {tmp}")
            time.sleep(0.5)
        load1 = loadavg()
    finally:
        # The node first: a rig stopping first would put it into the safe hold (in-process: the
        # manager, which ends both loops and writes both reports, then the loaders).
        bn.stop_processes(procs, logs)
    with open(node_report) as f:
        node = json.load(f)
    with open(rig_report) as f:
        rig = json.load(f)
    return {"rate": rate, "node": node, "rig": rig, "load": f"{load0} -> {load1}"}


def us(x):
    return f"{1e6 * x:.0f}" if x is not None else "-"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rates", default="1000,2000,5000", help="Hz, comma separated")
    ap.add_argument("--durations", default="60,60,60", help="s of wall clock per rate, comma separated")
    ap.add_argument("--chrt", type=int, default=0, help="SCHED_FIFO priority for node and rig (0: normal)")
    ap.add_argument("--inprocess", action="store_true",
                    help="node and rig as nodelets in one manager (shared pointers, no sockets)")
    ap.add_argument("--watch-outputs", action="store_true",
                    help="subscribe to pantograph_state and wire_shape (rostopic hz) during the run")
    ap.add_argument("--spin-wait", type=float, default=None,
                    help="s, the node's ~hil/spin_wait (default: the node's default)")
    args = ap.parse_args()
    rates = [float(r) for r in args.rates.split(",")]
    durations = [float(d) for d in args.durations.split(",")]
    if len(durations) == 1:
        durations *= len(rates)
    if len(durations) != len(rates):
        ap.error("--durations needs one value, or one per rate")
    for exe in ("catenary_sim_hil_node", "virtual_rig") + (("../libcatenary_sim_nodelets.so",) if args.inprocess else ()):
        if not os.access(os.path.join(LIB, exe), os.R_OK):
            sys.exit(f"bench_hil_latency: {LIB}/{exe} missing: run SKIP_SETUP=1 scripts/build first")

    env = bn.private_roscore("bench_hil_")

    results = []
    for rate, duration in zip(rates, durations):
        bn.log(f"{rate:g} Hz for {duration:g} s ...")
        r = run_rate(rate, duration, env, bn._tmp, args.chrt, args.spin_wait, args.inprocess, args.watch_outputs)
        results.append(r)
        n = r["node"]
        bn.log(f"  {n['periods']} periods, {n['overruns']} overruns, latency p99 {us(n['latency']['p99_s'])} us")

    print("| rate | dt x steps | wall (s) | periods | overruns | held | latency p50 / p99 / p99.9 / max (us) | "
          "compute p50 / p99 / max (us) | rig round trip p50 / p99 / max (us) | load avg |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    ok = True
    for r in results:
        n, g = r["node"], r["rig"]
        lat, comp, rt = n["latency"], n["compute"], g["round_trip"]
        held = n["periods_held"] / n["periods"] if n["periods"] else float("nan")
        print(f"| {r['rate']:g} Hz | {1e3 * n['dt_s']:g} ms x {n['steps_per_period']} | {n['wall_s']:.1f} | "
              f"{n['periods']} | {n['overruns']} | {100 * held:.2f} % | "
              f"{us(lat['p50_s'])} / {us(lat['p99_s'])} / {us(lat['p999_s'])} / {us(lat['max_s'])} | "
              f"{us(comp['p50_s'])} / {us(comp['p99_s'])} / {us(comp['max_s'])} | "
              f"{us(rt['p50_s'])} / {us(rt['p99_s'])} / {us(rt['max_s'])} | {r['load']} |")
        if r["rate"] == 1000.0:
            met = lat["p99_s"] < TARGETS["p99_max_s"] and n["overruns"] <= TARGETS["overruns"]
            ok = ok and met
            print(f"\n1 kHz target (latency p99 < 0.5 ms, no overruns over {n['wall_s']:.0f} s): "
                  f"{'met' if met else 'NOT met'}")
    print()
    for r in results:
        n = r["node"]
        print(f"{r['rate']:g} Hz: {n['measurements_accepted']} measurements, {n['measurements_superseded']} superseded, "
              f"{n['periods_triggered']} periods started by a measurement, {n['safe_holds']} safe holds, "
              f"max age while running {1e3 * n['max_age_running_s']:.2f} ms, {n['passes']} passes, "
              f"transport p50 {us(n['transport']['p50_s'])} us p99 {us(n['transport']['p99_s'])} us, "
              f"rig missed ticks {r['rig']['missed_ticks']}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
