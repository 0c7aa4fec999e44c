"""package.xml declares what the package needs, so that `rosdep install --from-paths` can install
it: every library CMakeLists.txt finds and every third-party module the Python tools import has
its rosdep key in package.xml."""
import ast
import os
import re
import sys

from catkin_pkg.package import parse_package

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# rosdep keys of what CMakeLists.txt finds with find_package (ROS packages go by their own names).
CMAKE_KEYS = {
    "Eigen3": "eigen", "yaml-cpp": "yaml-cpp", "nlohmann_json": "nlohmann-json-dev",
    "CLI11": "cli11", "pybind11": "pybind11-dev", "Python3": "python3-dev", "Threads": None,
    "catkin": "catkin", "nodelet": "nodelet", "pluginlib": "pluginlib", "rostest": "rostest",
}
# rosdep keys of the third-party Python modules (standard-library modules need none).
PYTHON_KEYS = {
    "numpy": "python3-numpy", "scipy": "python3-scipy", "pandas": "python3-pandas",
    "matplotlib": "python3-matplotlib", "yaml": "python3-yaml", "tqdm": "python3-tqdm",
    "dask": "python3-dask", "distributed": "python3-distributed", "rospy": "rospy",
    "rosgraph": "rosgraph", "std_msgs": "std_msgs", "std_srvs": "std_srvs",
    "geometry_msgs": "geometry_msgs", "rosbag": "rosbag", "pytest": "python3-pytest",
}
OWN = {"catenary_sim"}


def declared():
    p = parse_package(ROOT)
    deps = p.build_depends + p.exec_depends + p.test_depends + p.buildtool_depends
    return {d.name for d in deps}


def python_files():
    dirs = [os.path.join(ROOT, d) for d in ("scripts", "python")]
    for d in dirs:
        for base, _, files in os.walk(d):
            for f in files:
                path = os.path.join(base, f)
                if f.endswith(".py"):
                    yield path
                    continue
                with open(path, "rb") as fh:
                    first = fh.readline()
                if b"python" in first and first.startswith(b"#!"):
                    yield path


def imported_modules(path):
    with open(path, encoding="utf-8") as fh:
        tree = ast.parse(fh.read(), path)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.module.split(".")[0]


def test_every_library_cmake_finds_is_declared():
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as fh:
        text = fh.read()
    found = set(re.findall(r"find_package\(\s*([A-Za-z0-9_\-]+)", text))
    unknown = found - set(CMAKE_KEYS)
    assert not unknown, f"find_package of {sorted(unknown)}: add its rosdep key to package.xml and CMAKE_KEYS"
    missing = {CMAKE_KEYS[n] for n in found if CMAKE_KEYS[n]} - declared()
    assert not missing, f"package.xml lacks {sorted(missing)}"


def test_every_third_party_python_module_is_declared():
    stdlib = set(sys.stdlib_module_names)
    local = {os.path.splitext(f)[0] for f in os.listdir(os.path.join(ROOT, "scripts"))}
    needed = {}
    for path in python_files():
        for m in imported_modules(path):
            if m in stdlib or m in OWN or m in local:
                continue
            needed.setdefault(m, os.path.relpath(path, ROOT))
    unknown = {m: f for m, f in needed.items() if m not in PYTHON_KEYS}
    assert not unknown, f"imports without a known rosdep key (add to package.xml and PYTHON_KEYS): {unknown}"
    missing = {PYTHON_KEYS[m] for m in needed} - declared()
    assert not missing, f"package.xml lacks {sorted(missing)} (imported by {needed})"
