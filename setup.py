"""Builds the nbv Python package with CMake for `pip install .` (see pyproject.toml).

The CMake build lives in build-pip/ beside the sources (beside the Makefile's build/, so that
ccache serves the same compilations to both), is configured for the interpreter running pip,
and installs CMake's "wheel" component (the module, the nbv libraries, the Python files) into
the package's build folder.
"""
import os
import re
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))


def version():
    """The project's version, as CMakeLists.txt names it."""
    with open(os.path.join(HERE, "CMakeLists.txt"), encoding="utf-8") as f:
        return re.search(r"project\(nbv VERSION ([0-9.]+)", f.read()).group(1)


def check_interpreter():
    """nbv needs numpy at run time and `wheel` to be packed: say so, and what to do, before
    anything is built for a Python without them (often another Python first on PATH)."""
    missing = []
    for module in ("numpy", "wheel"):
        try:
            __import__(module)
        except ImportError:
            missing.append(module)
    if missing:
        sys.exit(f"nbv: {sys.executable} has no {' and no '.join(missing)}, which building nbv with it needs. "
                 "Use Debian's Python, which has them (apt-get install python3-numpy python3-wheel python3-venv): "
                 "/usr/bin/python3 -m venv --system-site-packages v && v/bin/pip install --no-build-isolation .")


check_interpreter()


class CMakeBuild(build_ext):
    """Configures, builds and installs the CMake component "wheel" instead of compiling sources."""

    def build_extension(self, ext):
        build = os.path.join(HERE, "build-pip")
        package = os.path.dirname(os.path.abspath(self.get_ext_fullpath(ext.name)))
        jobs = str(os.cpu_count() or 1)
        env = dict(os.environ, CCACHE_BASEDIR=HERE, CCACHE_NOHASHDIR="1")
        configure = ["cmake", "-S", HERE, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DNBV_PYTHON_WHEEL=ON",
                     f"-DNBV_PYTHON_EXECUTABLE={sys.executable}", "-DNBV_PYTHON_INSTALL_DIR:STRING=.",
                     "-DNBV_BUILD_TESTS=OFF", "-DNBV_BUILD_BENCHMARKS=OFF", "-DNBV_BUILD_APPS=OFF",
                     "-DNBV_BUILD_EXAMPLES=OFF"]
        for command in (configure, ["cmake", "--build", build, "--target", "nbv_python", "-j", jobs],
                        ["cmake", "--install", build, "--component", "wheel", "--prefix",
                         os.path.dirname(package)]):
            subprocess.run(command, check=True, env=env)


setup(
    version=version(),
    packages=["nbv"],
    package_dir={"": "python"},
    ext_modules=[Extension("nbv._nbv", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": "build-pip/setuptools"}, "egg_info": {"egg_base": "build-pip"}},
    zip_safe=False,
)
