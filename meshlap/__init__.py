"""meshlap: the Belkin–Sun–Wang heat-kernel mesh Laplacian as a scipy.sparse operator.

Belkin, Sun and Wang, "Discrete Laplace operator on meshed surfaces", SoCG 2008.

>>> import meshlap
>>> V, F = meshlap.shapes.sphere(500, seed=0)
>>> op = meshlap.laplacian(V, F, h=0.01)
>>> op.L.shape
(500, 500)
"""

from . import (
    baselines,
    curvature,
    geometry,
    heat,
    io,
    pointcloud,
    reproduce,
    samples,
    shapes,
    smoothing,
    spectral,
    topology,
)
from .geometry import Geometry, Polygons
from .mass import face_areas, vertex_mass
from .operator import (
    DEFAULT_TOL,
    MeshLaplacian,
    OperatorTooLargeError,
    default_h,
    laplacian,
    mesh_laplacian,
    truncation_bound,
)
from .pointcloud import point_cloud_laplacian
from .validation import MeshError, MeshWarning

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_TOL",
    "Geometry",
    "MeshError",
    "MeshLaplacian",
    "MeshWarning",
    "baselines",
    "curvature",
    "geometry",
    "heat",
    "io",
    "reproduce",
    "samples",
    "smoothing",
    "spectral",
    "OperatorTooLargeError",
    "Polygons",
    "default_h",
    "face_areas",
    "laplacian",
    "mesh_laplacian",
    "point_cloud_laplacian",
    "pointcloud",
    "shapes",
    "topology",
    "truncation_bound",
    "vertex_mass",
]
