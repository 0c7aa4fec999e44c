"""`rosrun catenary_sim TOOL` after `source .ws/devel/setup.bash`, as README.md and docs/ write it.

rosrun looks for the tool with `find -L` over the package (the repository, where the build lies in
.ws/) and over its devel space: the build must neither link the package back into itself (find then
reports a file system loop on every call) nor leave a second executable of the same name there
(rosrun then asks which one to run and waits on stdin, which hangs a script).

Run by scripts/run_tests after the build."""
import os
import subprocess
import tempfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SETUP = os.path.join(ROOT, ".ws", "devel", "setup.bash")
LIB = os.path.join(ROOT, ".ws", "devel", "lib", "catenary_sim")


def is_elf(path):
    with open(path, "rb") as f:
        return f.read(4) == b"\x7fELF"


@pytest.fixture(scope="module")
def env():
    if not os.path.isfile(SETUP):
        pytest.fail(".ws/devel/setup.bash is missing: build first (scripts/build)")
    # A user's shell with no workspace sourced; rospack's cache in a directory of the test's own.
    e = {k: v for k, v in os.environ.items()
         if not k.startswith(("ROS_", "CMAKE_PREFIX_PATH", "PKG_CONFIG_PATH", "PYTHONPATH", "LD_LIBRARY_PATH"))}
    e["PATH"] = "/usr/bin:/bin:/usr/sbin:/sbin"
    with tempfile.TemporaryDirectory(prefix="catenary_sim_rosrun_") as home:
        e["ROS_HOME"] = home
        yield e


def run_sourced(script, args, env):
    return subprocess.run(["bash", "-c", 'source "$0" && ' + script, SETUP] + list(args), env=env,
                          stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=600)


def test_rosrun_runs_simulate_pass_without_a_find_warning(env):
    r = run_sourced('rosrun catenary_sim simulate_pass --help', [], env)
    assert r.returncode == 0, r.stdout[-4000:]
    assert "find:" not in r.stdout, r.stdout[-4000:]
    assert "--scene" in r.stdout, r.stdout[-4000:]


def compiled_programs():
    return sorted(n for n in os.listdir(LIB)
                  if os.path.isfile(os.path.join(LIB, n)) and os.access(os.path.join(LIB, n), os.X_OK)
                  and is_elf(os.path.join(LIB, n)))


def test_rosrun_finds_the_documented_programs_once(env):
    # `--prefix echo` prints the path rosrun chose instead of running the program; a choice it
    # cannot make shows as its question and an empty path.
    names = ["simulate_pass", "pantograph_frf", "elasticity_curve", "catenary_sim_node", "catenary_sim_hil_node",
             "catenary_sim_hil_udp_node", "virtual_rig", "udp_rig_client", "replay_markers"]
    assert set(names) <= set(compiled_programs())
    r = run_sourced('for n in "$@"; do echo "== $n"; rosrun --prefix echo catenary_sim "$n"; done', names, env)
    assert r.returncode == 0, r.stdout[-4000:]
    found = {}
    name = None
    for line in r.stdout.splitlines():
        if line.startswith("== "):
            name = line[3:]
            found[name] = []
        else:
            found.setdefault(name, []).append(line)
    assert sorted(found) == sorted(names), r.stdout[-4000:]
    wrong = {n: lines for n, lines in found.items()
             if [os.path.realpath(p) for p in lines] != [os.path.realpath(os.path.join(LIB, n))]}
    assert not wrong, wrong


PYTHON_NODES = ["record_until_end", "catenary_sim_study", "plot_contact_force", "fit_pantograph", "pass_report",
                "plot_frf", "compare_measurement", "calibrate"]


def test_rosrun_finds_each_python_node_once(env):
    # The Python nodes run from their sources in scripts/: a second file of the same name in the
    # devel space or the build tree makes rosrun ask which one, and wait on stdin.
    r = run_sourced('for n in "$@"; do echo "== $n"; rosrun --prefix echo catenary_sim "$n"; done', PYTHON_NODES,
                    env)
    assert r.returncode == 0, r.stdout[-4000:]
    found, name = {}, None
    for line in r.stdout.splitlines():
        if line.startswith("== "):
            name = line[3:]
            found[name] = []
        else:
            found[name].append(line)
    wrong = {n: found.get(n) for n in PYTHON_NODES
             if [os.path.realpath(p) for p in found.get(n, [])] != [os.path.realpath(os.path.join(ROOT, "scripts", n))]}
    assert not wrong, wrong


def test_rosrun_runs_a_python_node(env):
    # pass_report needs no master: its help comes back at once.
    r = run_sourced('rosrun catenary_sim pass_report --help', [], env)
    assert r.returncode == 0, r.stdout[-4000:]
    assert "non-unique" not in r.stdout and "usage:" in r.stdout, r.stdout[-4000:]


def test_the_package_holds_one_executable_of_each_compiled_programs_name():
    # What rosrun's search sees of every other program, in one walk instead of a rosrun each: the
    # package followed through its links (`find -L`, build/ at the top left out as rosrun does),
    # where a compiled program must lie once, in the devel space, and a Python node once, in scripts/.
    names = compiled_programs() + PYTHON_NODES
    root = os.path.realpath(ROOT)
    r = subprocess.run(["find", "-L", root, "-type", "f", "-perm", "/111"], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, timeout=600)
    assert r.stderr == "", r.stderr[-4000:]
    found = {}
    for path in r.stdout.splitlines():
        if os.path.basename(path) in names and not path.startswith(os.path.join(root, "build") + "/"):
            found.setdefault(os.path.basename(path), []).append(path)
    def home(n):
        return os.path.join(root, "scripts", n) if n in PYTHON_NODES else os.path.join(os.path.realpath(LIB), n)
    wrong = {n: found.get(n) for n in names if found.get(n) != [home(n)]}
    assert not wrong, wrong
