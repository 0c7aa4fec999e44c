# catkin_python_setup(): the pure-Python part of `import catenary_sim` (python/catenary_sim); the
# pybind11 extension catenary_sim._core is built by CMakeLists.txt into the same package.
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["catenary_sim"], package_dir={"": "python"}))
