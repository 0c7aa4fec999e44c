"""An installed catenary_sim carries no path of the tree it was built in: the install space is made
under a staging directory of the test's own (make install DESTDIR=...), so that a binary still
looking beside its sources or at the configured install prefix finds nothing there. Every
installed binary and library is searched for the package's source and build paths (`strings`),
and simulate_pass --report runs from the staged copy with no workspace sourced: it must find
scripts/pass_report and config/ in share/catenary_sim beside its own lib/.

Run by scripts/run_tests after the build (it installs the built workspace)."""
import json
import os
import shutil
import subprocess
import tempfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
REAL_ROOT = os.path.realpath(ROOT)
WS = os.path.join(ROOT, ".ws")


def clean_env():
    """The environment of a user's shell with no workspace sourced, Debian's Python first."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("ROS_", "CMAKE_PREFIX_PATH", "PKG_CONFIG_PATH", "PYTHONPATH", "LD_LIBRARY_PATH",
                                "CATENARY_SIM"))}
    env["PATH"] = "/usr/bin:/bin:/usr/sbin:/sbin"
    return env


def install_prefix():
    """CMAKE_INSTALL_PREFIX of the build tree (where make install puts the files under DESTDIR)."""
    with open(os.path.join(WS, "build", "CMakeCache.txt")) as f:
        for line in f:
            if line.startswith("CMAKE_INSTALL_PREFIX:"):
                return line.split("=", 1)[1].strip()
    pytest.fail("CMAKE_INSTALL_PREFIX not in .ws/build/CMakeCache.txt")


@pytest.fixture(scope="module")
def staged():
    if not os.path.isdir(os.path.join(WS, "build")):
        pytest.fail(".ws/build is missing: build first (scripts/build)")
    stage = tempfile.mkdtemp(prefix="catenary_sim_stage_")
    try:
        env = clean_env()
        env["DESTDIR"] = stage
        r = subprocess.run(["make", "-C", os.path.join(WS, "build"), "install"], env=env,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1800)
        assert r.returncode == 0, r.stdout[-4000:]
        prefix = stage + install_prefix()
        assert os.path.isfile(os.path.join(prefix, "lib", "catenary_sim", "simulate_pass"))
        yield prefix
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def is_elf(path):
    with open(path, "rb") as f:
        return f.read(4) == b"\x7fELF"


def installed_binaries(prefix):
    """Executables, shared objects and static libraries of the install space."""
    found = []
    for top, _, names in os.walk(prefix):
        for name in names:
            path = os.path.join(top, name)
            if os.path.islink(path) or not os.path.isfile(path):
                continue
            if name.endswith(".a") or is_elf(path):
                found.append(path)
    return found


def test_installed_binaries_carry_no_source_or_build_path(staged):
    binaries = installed_binaries(staged)
    names = {os.path.basename(p) for p in binaries}
    # The tools, the nodes, the libraries and the Python module are all looked at.
    for expected in ("simulate_pass", "pantograph_frf", "catenary_sim_node", "libcatenary_sim_core.a",
                     "libcatenary_sim_tools.a", "libcatenary_sim_ros.a", "libcatenary_sim_nodelets.so"):
        assert expected in names, sorted(names)
    assert any(n.startswith("_core") and n.endswith(".so") for n in names), sorted(names)
    # The package's tree (its sources, .ws/build, .ws/devel) by both of its names: the checkout
    # resolves to REAL_ROOT, ROOT is how the build was started.
    paths = {ROOT, REAL_ROOT}
    offenders = []
    for path in binaries:
        text = subprocess.run(["strings", "-a", path], stdout=subprocess.PIPE, check=True).stdout.decode(
            "utf-8", "replace")
        hits = sorted({line for line in text.splitlines() if any(p in line for p in paths)})
        if hits:
            offenders.append("%s: %s" % (os.path.relpath(path, staged), hits[:3]))
    assert not offenders, "\n".join(offenders)


def test_simulate_pass_report_runs_from_the_install_space(staged):
    share = os.path.join(staged, "share", "catenary_sim")
    scene = os.path.join(share, "config", "reference_55m.yaml")
    assert os.path.isfile(scene)
    with tempfile.TemporaryDirectory(prefix="catenary_sim_installed_pass_") as work:
        out = os.path.join(work, "out")
        # Six 55 m spans at 250 km/h with 0.5 m elements: a pass of about two seconds (as
        # test/tools/test_pass_report.cpp), run from a directory outside the package.
        r = subprocess.run([os.path.join(staged, "lib", "catenary_sim", "simulate_pass"), "--scene", scene,
                            "--out", out, "--speed", "250", "--set", "line.span_count=6", "--set",
                            "numerics.element_length=0.5", "--report", "--quiet", "--no-progress"],
                           cwd=work, env=clean_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           timeout=600)
        assert r.returncode == 0, r.stdout[-4000:]
        with open(os.path.join(out, "stats.json")) as f:
            assert json.load(f)["pantographs"]
        with open(os.path.join(out, "report.html")) as f:
            assert "id='statistics'" in f.read()


def test_a_missing_report_script_names_where_it_was_looked_for(staged):
    # The staged copy without its share/catenary_sim/scripts: --report must say where it looked
    # (share/catenary_sim beside the binary), never fall back to the source tree.
    scripts = os.path.join(staged, "share", "catenary_sim", "scripts")
    hidden = scripts + ".hidden"
    os.rename(scripts, hidden)
    try:
        with tempfile.TemporaryDirectory(prefix="catenary_sim_installed_pass_") as work:
            r = subprocess.run([os.path.join(staged, "lib", "catenary_sim", "simulate_pass"), "--scene",
                                os.path.join(staged, "share", "catenary_sim", "config", "reference_55m.yaml"),
                                "--out", os.path.join(work, "out"), "--speed", "250", "--set", "line.span_count=6",
                                "--set", "numerics.element_length=0.5", "--report", "--quiet", "--no-progress"],
                               cwd=work, env=clean_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, timeout=600)
            assert r.returncode == 2, r.stdout[-4000:]
            assert "scripts/pass_report not found in " + os.path.join(staged, "share", "catenary_sim") in r.stdout, \
                r.stdout[-4000:]
            assert os.path.isfile(os.path.join(work, "out", "stats.json"))
    finally:
        os.rename(hidden, scripts)


def installed_pass(staged, work, *extra):
    """simulate_pass from the staged install, no workspace sourced: a short pass (as above)."""
    return subprocess.run([os.path.join(staged, "lib", "catenary_sim", "simulate_pass"), "--scene",
                           os.path.join(staged, "share", "catenary_sim", "config", "reference_55m.yaml"),
                           "--out", os.path.join(work, "out"), "--speed", "250", "--set", "line.span_count=6",
                           "--set", "numerics.element_length=0.5", "--quiet", "--no-progress", *extra],
                          cwd=work, env=clean_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=600)


def test_simulate_pass_writes_a_bag_from_the_install_space(staged):
    # The bag writer is a library simulate_pass loads for --bag alone: it must be installed in
    # lib/ beside lib/catenary_sim/ and found there with no workspace sourced.
    assert os.path.isfile(os.path.join(staged, "lib", "libcatenary_sim_pass_bag.so"))
    with tempfile.TemporaryDirectory(prefix="catenary_sim_installed_pass_") as work:
        bag = os.path.join(work, "pass.bag")
        r = installed_pass(staged, work, "--bag", bag)
        assert r.returncode == 0, r.stdout[-4000:]
        with open(bag, "rb") as f:
            assert f.read(13) == b"#ROSBAG V2.0\n"


def test_a_missing_bag_writer_fails_only_a_pass_that_asks_for_a_bag(staged):
    lib = os.path.join(staged, "lib", "libcatenary_sim_pass_bag.so")
    hidden = lib + ".hidden"
    os.rename(lib, hidden)
    try:
        with tempfile.TemporaryDirectory(prefix="catenary_sim_installed_pass_") as work:
            r = installed_pass(staged, work)
            assert r.returncode == 0, r.stdout[-4000:]
            bag = os.path.join(work, "pass.bag")
            r = installed_pass(staged, work, "--bag", bag)
            assert r.returncode == 2, r.stdout[-4000:]
            assert "libcatenary_sim_pass_bag.so cannot be loaded" in r.stdout, r.stdout[-4000:]
            assert not os.path.exists(bag) and not os.path.exists(bag + ".partial")
    finally:
        os.rename(hidden, lib)
