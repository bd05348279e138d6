"""The wheel's build step: compile the kernels of the first builds into the package.

Everything else is in pyproject.toml. ``build_py`` copies the package into the build folder and
then runs meshlap._prebuilt.build on that copy, which compiles the kernels in a subprocess and
writes them to ``meshlap/_kernels`` there (see that module). An editable install
(``pip install -e``) is left as it is: its kernels are compiled on first use.
"""

import importlib.util
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildWithKernels(build_py):
    def run(self):
        super().run()
        if self.editable_mode:
            return
        package = Path(self.build_lib) / "meshlap"
        # the module by its file: importing the package here would load the sources' copy
        spec = importlib.util.spec_from_file_location("_meshlap_prebuilt", package / "_prebuilt.py")
        prebuilt = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(prebuilt)
        prebuilt.build(package)


setup(cmdclass={"build_py": BuildWithKernels})
