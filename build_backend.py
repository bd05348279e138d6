"""setuptools' build backend, with meshlap's dependencies added to a wheel's build requirements.

The wheel's build step (setup.py) imports meshlap to compile its kernels, so building a wheel
needs what meshlap needs; an editable install and an sdist do not, and they keep setuptools
alone (an editable install's build environment would otherwise install numba, scipy, ... for
nothing). tests/test_packaging.py keeps the list equal to pyproject.toml's dependencies.
"""

from setuptools import build_meta
from setuptools.build_meta import *  # noqa: F403 - the backend's other hooks, unchanged

#: [project] dependencies in pyproject.toml
DEPENDENCIES = ["numpy>=1.24", "scipy>=1.10", "libigl>=2.6", "pykdtree>=1.3", "numba>=0.59",
                "threadpoolctl>=3", "qdldl>=0.1.9", "pyamg>=5"]


def get_requires_for_build_wheel(config_settings=None):
    return build_meta.get_requires_for_build_wheel(config_settings) + DEPENDENCIES
