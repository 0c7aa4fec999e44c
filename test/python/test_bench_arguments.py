"""The bench programs' command lines (bench/bench_*.cpp, CLI11): --help prints the program's usage
and exits 0; a bad argument ends with a message naming the argument and the value, a non-zero exit
status, and no benchmark run (nothing on standard output, no file written, within seconds)."""
import os
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEVEL = os.environ.get("CATENARY_SIM_DEVEL_LIB", os.path.join(ROOT, ".ws", "devel", "lib", "catenary_sim"))
REFERENCE = os.path.join(ROOT, "config", "reference_55m.yaml")

PROGRAMS = sorted(f[:-len(".cpp")] for f in os.listdir(os.path.join(ROOT, "bench"))
                  if f.startswith("bench_") and f.endswith(".cpp"))

# Per program, bad command lines: (arguments, the argument the message must name, the value it must
# quote). Each is refused by a different check: a range, a non-number, a member list, a missing file,
# an override that is not field=value, an unexpected extra argument.
BAD = {
    "bench_endless_soak": [(["--hours", "0"], "--hours", "0"),
                           (["--hours", "1", "--report", "nan"], "--report", "nan"),
                           (["--scene", "no_such_scene.yaml"], "--scene", "no_such_scene.yaml"),
                           (["--hours", "1", "junk"], "overrides", "junk")],
    "bench_gust_lead": [(["0"], "seeds", "0"), (["four"], "seeds", "four")],
    "bench_lateral": [(["abc"], "repetitions", "abc"), (["-3"], "repetitions", "-3"),
                      (["3", "-1"], "long_spans", "-1"), (["3", "0", "1.5"], "seeds", "1.5"),
                      (["3", "0", "0", "9"], "not expected", "9")],
    "bench_pass_hash": [([], "scene", "required"), (["no_such_scene.yaml"], "scene", "no_such_scene.yaml"),
                        ([REFERENCE, "numerics.preset"], "overrides", "numerics.preset")],
    "bench_reference_pass": [(["0"], "repetitions", "0"), (["5", "no_such_scene.yaml"], "scene", "no_such_scene.yaml")],
    "bench_reference_rung": [([REFERENCE, "out.csv", "0.03125", "bogus"], "mode", "bogus"),
                             ([REFERENCE, "out.csv", "-1"], "finest_h", "-1"),
                             ([REFERENCE, "out.csv", "0.03125", "window", "train.end"], "overrides", "train.end")],
    "bench_speed_accuracy": [(["no_such_scene.yaml"], "scene", "no_such_scene.yaml")],
    "bench_step_floor": [(["1", REFERENCE, "best"], "preset", "best"), (["1e9"], "repetitions", "1e9")],
    "bench_timer_jitter": [(["0"], "rate", "0"), (["1000", "inf"], "seconds", "inf")],
    "bench_window": [(["5"], "spans", "5"), (["many"], "spans", "many")],
    "bench_window_lengths": [(["150,abc"], "speeds_kmh", "abc"), (["150", "sweep"], "rows", "sweep")],
}


def run(program, args, cwd):
    try:
        return subprocess.run([os.path.join(DEVEL, program), *args], capture_output=True, text=True, cwd=cwd,
                              timeout=30)
    except subprocess.TimeoutExpired:
        pytest.fail("%s %s still running after 30 s: it ran the benchmark" % (program, " ".join(args)))


def test_every_bench_program_has_its_bad_arguments_here():
    assert PROGRAMS and sorted(BAD) == PROGRAMS


@pytest.mark.parametrize("program", PROGRAMS)
def test_help_prints_the_usage_and_exits_0(program, tmp_path):
    r = run(program, ["--help"], str(tmp_path))
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines and len(lines[0]) > 20, r.stdout  # the program's one-line description
    assert ("Usage: %s " % program) in r.stdout, r.stdout
    assert os.listdir(str(tmp_path)) == []


@pytest.mark.parametrize("program,args,name,value",
                         [(p, a, n, v) for p in sorted(BAD) for (a, n, v) in BAD[p]])
def test_a_bad_argument_is_refused_before_any_run(program, args, name, value, tmp_path):
    r = run(program, args, str(tmp_path))
    assert r.returncode > 0, (r.returncode, r.stdout, r.stderr)  # (negative: a signal)
    assert name in r.stderr and value in r.stderr, r.stderr
    assert r.stdout == "", r.stdout  # no table started
    assert os.listdir(str(tmp_path)) == []  # no CSV written
