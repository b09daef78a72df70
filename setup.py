"""Builds the Python package with CMake for `pip install .` (pyproject.toml, docs/python.md).

The extension module physgrad._physgrad is the CMake target physgrad_python of this repository,
built for the interpreter that runs the install; the pure-Python parts, the type stubs and
py.typed come from python/physgrad. CMake configures into the build folder setuptools gives
(or reuses the configured tree named by PHYSGRAD_CMAKE_BUILD_DIR); CMAKE_ARGS adds arguments
(e.g. -DCMAKE_CXX_COMPILER_LAUNCHER=ccache) and CMAKE_BUILD_PARALLEL_LEVEL sets the jobs (2).
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = Path(__file__).resolve().parent


def project_version():
    text = (SOURCE / "CMakeLists.txt").read_text(encoding="utf-8")
    return re.search(r"project\(physgrad VERSION ([0-9.]+)", text).group(1)


def interpreter_suffix(python):
    """The extension-module suffix (.cpython-311-x86_64-linux-gnu.so) of interpreter `python`."""
    done = subprocess.run([python, "-c", "import sysconfig; "
                           "print(sysconfig.get_config_var('EXT_SUFFIX'))"],
                          capture_output=True, text=True, check=False)
    return done.stdout.strip() if done.returncode == 0 else None


def check_build_tree(build, suffix=None):
    """Refuses (RuntimeError, one line) a configured tree whose Python is not one with this
    interpreter's ABI: its module would be copied in under the wrong tag."""
    suffix = suffix or sysconfig.get_config_var("EXT_SUFFIX")
    cache = Path(build) / "CMakeCache.txt"
    if not cache.is_file():
        raise RuntimeError(f"physgrad: PHYSGRAD_CMAKE_BUILD_DIR={build} is not a configured "
                           "CMake build tree (no CMakeCache.txt)")
    found = re.search(r"^Python3_EXECUTABLE:[A-Z]+=(.*)$", cache.read_text(errors="replace"),
                      re.M)
    python = found.group(1).strip() if found else ""
    theirs = interpreter_suffix(python) if python else None
    if theirs != suffix:
        raise RuntimeError(
            f"physgrad: the build tree {build} is configured for {python or 'no Python'} "
            f"(modules {theirs or 'unknown'}), not for {sys.executable} ({suffix}); reconfigure "
            f"it with -DPython3_EXECUTABLE={sys.executable} or leave PHYSGRAD_CMAKE_BUILD_DIR "
            "unset")


class CMakeBuild(build_ext):
    """Builds physgrad._physgrad by CMake and copies it where setuptools packs it."""

    def build_extension(self, ext):
        build = os.environ.get("PHYSGRAD_CMAKE_BUILD_DIR")
        if build:
            build = Path(build).resolve()
            check_build_tree(build)
        else:
            build = Path(self.build_temp).resolve() / "cmake"
            configure = ["cmake", "-S", str(SOURCE), "-B", str(build),
                         "-DCMAKE_BUILD_TYPE=Release", f"-DPython3_EXECUTABLE={sys.executable}",
                         "-DPHYSGRAD_BUILD_TESTS=OFF", "-DPHYSGRAD_BUILD_BENCHMARKS=OFF",
                         "-DPHYSGRAD_BUILD_EXAMPLES=OFF"]
            configure += shlex.split(os.environ.get("CMAKE_ARGS", ""))
            subprocess.run(configure, check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", "2")
        # CMake's own progress lines ([ 45%] Building CXX object …) go to the output; pip shows
        # them with -v (docs/python.md), else only its spinner.
        print(f"physgrad: building the extension module with CMake in {build} ({jobs} jobs)",
              file=sys.stderr, flush=True)
        subprocess.run(["cmake", "--build", str(build), "--target", "physgrad_python", "-j", jobs],
                       check=True)
        # This interpreter's module only: another one in the tree (built for another Python)
        # would be installed under the wrong ABI tag.
        built = build / "python" / "physgrad" / ("_physgrad" +
                                                 sysconfig.get_config_var("EXT_SUFFIX"))
        if not built.is_file():
            raise RuntimeError(f"physgrad: {built} was not built (the tree's Python is not "
                               f"{sys.executable}?)")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, target)


if __name__ == "__main__":  # pip runs this file as __main__; the tests import its checks
    setup(
        version=project_version(),
        package_dir={"": "python"},
        packages=["physgrad", "physgrad.torch"],
        package_data={"physgrad": ["py.typed", "*.pyi"], "physgrad.torch": ["*.pyi"]},
        ext_modules=[Extension("physgrad._physgrad", sources=[])],
        cmdclass={"build_ext": CMakeBuild},
        zip_safe=False,
    )
