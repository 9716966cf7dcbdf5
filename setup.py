"""Builds the Python package accelcal with the project's CMake (pyproject.toml).

The extension module accelcal._accelcal is the CMake target accelcal_python, configured in
setuptools' temporary directory with only the library and the module (no tool, tests or
benchmarks) for the interpreter that runs the build; the package's Python files come from
python/accelcal. Environment: CMAKE_BUILD_PARALLEL_LEVEL (jobs; default: every core),
ACCELCAL_CMAKE_ARGS (more arguments for CMake's configure step, split on spaces),
ACCELCAL_CMAKE_BUILD_DIR (CMake's build directory; default: in setuptools' temporary one).
"""
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


def project_version():
    """The version of CMakeLists.txt's project(), the one the library and accelcal.__version__
    state."""
    text = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\(accelcal\s+VERSION\s+([0-9.]+)", text)
    if not match:
        raise RuntimeError("CMakeLists.txt: no 'project(accelcal VERSION x.y.z' line")
    return match.group(1)


class CMakeExtension(Extension):
    def __init__(self, name, target):
        super().__init__(name, sources=[])
        self.target = target


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        if not isinstance(ext, CMakeExtension):
            return super().build_extension(ext)
        build_dir = Path(os.environ.get("ACCELCAL_CMAKE_BUILD_DIR") or
                         Path(self.build_temp) / "cmake").resolve()
        build_dir.mkdir(parents=True, exist_ok=True)
        config = "Debug" if self.debug else "Release"
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(build_dir),
            f"-DCMAKE_BUILD_TYPE={config}",
            f"-DPython_EXECUTABLE={sys.executable}",
            "-DACCELCAL_BUILD_PYTHON=ON", "-DACCELCAL_BUILD_CLI=OFF",
            "-DACCELCAL_BUILD_TESTS=OFF", "-DACCELCAL_BUILD_BENCHMARKS=OFF",
            "-DACCELCAL_INSTALL=OFF", "-DBUILD_SHARED_LIBS=OFF",
        ]
        configure += os.environ.get("ACCELCAL_CMAKE_ARGS", "").split()
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        subprocess.run(configure, check=True)
        subprocess.run(["cmake", "--build", str(build_dir), "--target", ext.target,
                        "--parallel", jobs], check=True)
        built = build_dir / "python" / "accelcal" / Path(self.get_ext_filename(ext.name)).name
        if not built.is_file():
            raise RuntimeError(f"CMake did not build {built}")
        destination = Path(self.get_ext_fullpath(ext.name))
        destination.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, destination)


setup(
    version=project_version(),
    packages=["accelcal"],
    package_dir={"": "python"},
    package_data={"accelcal": ["py.typed", "*.pyi"]},
    ext_modules=[CMakeExtension("accelcal._accelcal", target="accelcal_python")],
    cmdclass={"build_ext": CMakeBuild},
    # Beside the CMake build of scripts/test.sh (build/), not in it.
    options={"build": {"build_base": "build-python"}},
    zip_safe=False,
)
