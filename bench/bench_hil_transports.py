#!/usr/bin/python3
"""The hardware-in-the-loop loop over three transports, in one run (as rigs run it).

  bench/bench_hil_transports.py [--rates 1000,5000,10000] [--duration 30]

For each rate, one after the other on the same machine: the loop (config/reference_55m_hil.yaml,
300 km/h, the pass repeated) closed with the simulated rig (the reference lumped pantograph,
sending on its own clock at the loop rate) over
  udp        catenary_sim_hil_udp + udp_rig_client: the packets of hil/udp_packets.h on loopback
             (no ROS master, no ROS at all)
  tcpros     catenary_sim_hil_node + virtual_rig over hil/contact_force and hil/contact_point
  inprocess  both as nodelets in one manager (shared pointers, no socket)
then bench_timer_jitter (a bare periodic thread) at the same rate for the machine's own floor.
From each loop's report: latency (measurement arrival -> the contact point computed with it
sent) p50 / p99 / max, overruns, held periods, and the loop's own jitter (how late each period
started) p99 / max. Speeds are compared within this run only (ratios), the machine being shared.

Uses bench_hil_latency.py's run_rate for the two ROS transports (a private roscore on a free
port); everything started here is stopped on exit. Build first: SKIP_SETUP=1 scripts/build.
"""
import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import bench_hil_latency as hl  # noqa: E402
import bench_node as bn  # noqa: E402

ROOT = bn.ROOT
LIB = hl.LIB


def run_udp(rate, duration, tmp):
    label = f"{int(rate)}hz"
    report = os.path.join(tmp, f"udp_{label}.json")
    port = bn.free_port()
    sim = [os.path.join(LIB, "catenary_sim_hil_udp"), "--scene", os.path.join(ROOT, "config", "reference_55m_hil.yaml"),
           "--rate", str(rate), "--timeout", "0.05", "--at-end", "loop", "--bind", "127.0.0.1", "--port", str(port),
           "--same-clock", "--duration", str(duration), "--report", report]
    rig = [os.path.join(LIB, "udp_rig_client"), "--pantograph-scene", os.path.join(ROOT, "config", "reference_55m.yaml"),
           "--simulator", f"127.0.0.1:{port}", "--keep-running"]
    logs = [open(os.path.join(tmp, f"{n}_udp_{label}.log"), "w") for n in ("sim", "rig")]
    procs = []
    load0 = hl.loadavg()
    try:
        for cmd, log in zip((sim, rig), logs):
            p = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                 start_new_session=True)
            bn._started.append(p)
            procs.append(p)
        if procs[0].wait(timeout=duration + 60) != 0:
            raise RuntimeError(f"catenary_sim_hil_udp exited with {procs[0].returncode}; see {tmp}")
        load1 = hl.loadavg()
    finally:
        bn.stop_processes(list(reversed(procs)), logs)
    with open(report) as f:
        return {"node": json.load(f), "load": f"{load0} -> {load1}"}


def timer_jitter(rate, seconds):
    out = subprocess.run([os.path.join(LIB, "bench_timer_jitter"), str(rate), str(seconds)], capture_output=True,
                         text=True, check=True).stdout.strip()
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rates", default="1000,5000,10000", help="Hz, comma separated")
    ap.add_argument("--duration", type=float, default=30.0, help="s of wall clock per transport and rate")
    args = ap.parse_args()
    rates = [float(r) for r in args.rates.split(",")]
    for exe in ("catenary_sim_hil_udp", "udp_rig_client", "catenary_sim_hil_node", "virtual_rig", "bench_timer_jitter"):
        if not os.access(os.path.join(LIB, exe), os.X_OK):
            sys.exit(f"bench_hil_transports: {LIB}/{exe} missing: run SKIP_SETUP=1 scripts/build first")
    env = bn.private_roscore("bench_hil_transports_")
    rows = []
    for rate in rates:
        for transport in ("udp", "tcpros", "inprocess"):
            bn.log(f"{rate:g} Hz over {transport} for {args.duration:g} s ...")
            if transport == "udp":
                r = run_udp(rate, args.duration, bn._tmp)
            else:
                r = hl.run_rate(rate, args.duration, env, bn._tmp, 0, None, transport == "inprocess", False)
            rows.append((rate, transport, r))
        bn.log(f"{rate:g} Hz bench_timer_jitter ...")
        rows.append((rate, "timer", timer_jitter(rate, min(args.duration, 20.0))))
    print("| rate | transport | periods | overruns | held | latency p50 / p99 / max (us) | loop jitter p99 / max (us) | load avg |")
    print("|---|---|---|---|---|---|---|---|")
    p99 = {}
    for rate, transport, r in rows:
        if transport == "timer":
            print(f"| {rate:g} Hz | bare timer thread | {r} | | | | | |")
            continue
        n = r["node"]
        lat = n["latency"]
        jit = n.get("jitter", {})
        held = n["periods_held"] / n["periods"] if n["periods"] else float("nan")
        p99[(rate, transport)] = lat["p99_s"]
        print(f"| {rate:g} Hz | {transport} | {n['periods']} | {n['overruns']} | {100 * held:.2f} % | "
              f"{hl.us(lat['p50_s'])} / {hl.us(lat['p99_s'])} / {hl.us(lat['max_s'])} | "
              f"{hl.us(jit.get('p99_s'))} / {hl.us(jit.get('max_s'))} | {r['load']} |")
    print()
    for rate in rates:
        u, t, i = (p99.get((rate, k)) for k in ("udp", "tcpros", "inprocess"))
        if u and t and i:
            print(f"{rate:g} Hz latency p99 ratios: tcpros / udp {t / u:.2f}, inprocess / udp {i / u:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
