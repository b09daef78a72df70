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
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = Path(__file__).resolve().parent


def project_version():
    text = (SOURCE / "CMakeLists.txt").read_text(encoding="utf-8")
    return re.search(r"project\(physgrad VERSION ([0-9.]+)", text).group(1)


class CMakeBuild(build_ext):
    """Builds physgrad._physgrad by CMake and copies it where setuptools packs it."""

    def build_extension(self, ext):
        build = os.environ.get("PHYSGRAD_CMAKE_BUILD_DIR")
        if build:
            build = Path(build).resolve()
        else:
            build = Path(self.build_temp).resolve() / "cmake"
            configure = ["cmake", "-S", str(SOURCE), "-B", str(build),
                         "-DCMAKE_BUILD_TYPE=Release", f"-DPython3_EXECUTABLE={sys.executable}",
                         "-DPHYSGRAD_BUILD_TESTS=OFF", "-DPHYSGRAD_BUILD_BENCHMARKS=OFF",
                         "-DPHYSGRAD_BUILD_EXAMPLES=OFF"]
            configure += shlex.split(os.environ.get("CMAKE_ARGS", ""))
            subprocess.run(configure, check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", "2")
        subprocess.run(["cmake", "--build", str(build), "--target", "physgrad_python", "-j", jobs],
                       check=True)
        built = sorted((build / "python" / "physgrad").glob("_physgrad*.so"))
        if not built:
            raise RuntimeError(f"physgrad: no extension module in {build}/python/physgrad")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built[-1], target)


setup(
    version=project_version(),
    package_dir={"": "python"},
    packages=["physgrad", "physgrad.torch"],
    package_data={"physgrad": ["py.typed", "*.pyi"], "physgrad.torch": ["*.pyi"]},
    ext_modules=[Extension("physgrad._physgrad", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    zip_safe=False,
)
