"""catenary_sim as a dependency of another ROS package: test/downstream/catenary_sim_downstream is
built in a workspace of its own against catenary_sim's install space (not its sources, not its
devel space), with nothing but `find_package(catkin REQUIRED COMPONENTS catenary_sim)`, and runs a
pass through the exported headers and libraries.

Run by scripts/run_tests after the build (it installs the built workspace into .ws/install)."""
import os
import shutil
import subprocess
import tempfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
WS = os.path.join(ROOT, ".ws")
INSTALL = os.path.join(WS, "install")
PACKAGE = os.path.join(ROOT, "test", "downstream", "catenary_sim_downstream")


def clean_env():
    """The environment of a user's shell with no workspace sourced, Debian's Python first."""
    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("ROS_", "CMAKE_PREFIX_PATH", "PKG_CONFIG_PATH", "PYTHONPATH", "LD_LIBRARY_PATH"))}
    env["PATH"] = "/usr/bin:/bin:/usr/sbin:/sbin"
    return env


def sourced(cmd, setup):
    return ["bash", "-c", f"source '{setup}' && {cmd}"]


@pytest.fixture(scope="module")
def install_space():
    if not os.path.isdir(os.path.join(WS, "build")):
        pytest.fail(".ws/build is missing: build first (scripts/build)")
    # The install space lies inside the package's own tree (.ws/install), where `rosrun
    # catenary_sim TOOL` would then find each tool twice and refuse to choose: the test removes
    # the install space it made once it is done.
    made = not os.path.exists(INSTALL)
    try:
        r = subprocess.run(["make", "-C", os.path.join(WS, "build"), "install"], env=clean_env(),
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1800)
        assert r.returncode == 0, r.stdout[-4000:]
        assert os.path.isfile(os.path.join(INSTALL, "setup.bash"))
        yield INSTALL
    finally:
        if made:
            shutil.rmtree(INSTALL, ignore_errors=True)


def test_a_downstream_package_builds_against_the_install_space_and_runs_a_pass(install_space):
    with tempfile.TemporaryDirectory(prefix="catenary_sim_downstream_") as ws:
        shutil.copytree(PACKAGE, os.path.join(ws, "src", "catenary_sim_downstream"))
        r = subprocess.run(sourced(f"catkin_make -C '{ws}' -j2", os.path.join(install_space, "setup.bash")),
                           env=clean_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           timeout=900)
        assert r.returncode == 0, r.stdout[-6000:]
        assert "warning:" not in r.stdout, r.stdout[-6000:]
        exe = os.path.join(ws, "devel", "lib", "catenary_sim_downstream", "downstream_pass")
        # The scene as installed with the package (share/catenary_sim/config).
        scene = os.path.join(install_space, "share", "catenary_sim", "config", "reference_55m.yaml")
        assert os.path.isfile(scene)
        run = subprocess.run(sourced(f"'{exe}' '{scene}'", os.path.join(ws, "devel", "setup.bash")),
                             env=clean_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             timeout=600)
        assert run.returncode == 0, run.stderr
        fields = run.stdout.split()
        values = dict(zip(fields[0::2], fields[1::2]))
        assert int(values["finished"]) == 1
        assert int(values["steps"]) > 1000
        # The reference pantograph has no aerodynamic term, so its mean contact force over a pass is
        # its static uplift, 100 N, up to the change of its momentum and of its damper's stroke
        # between the pass's start and end divided by the pass's duration: 22.5 kg x a few 0.1 m/s
        # and 100 N s/m x a few cm over 6.6 s, each below 1 N. 3 % holds both with room.
        assert float(values["mean_contact_force_n"]) == pytest.approx(100.0, rel=0.03)
