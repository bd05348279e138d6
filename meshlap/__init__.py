"""meshlap: the Belkin–Sun–Wang heat-kernel mesh Laplacian as a scipy.sparse operator.

Belkin, Sun and Wang, "Discrete Laplace operator on meshed surfaces", SoCG 2008.

The operator is built along one pipeline, the same for meshes, point clouds, curves,
volumes and the rows of one MPI rank:

    input → geometry (Geometry) → widths → assembly (Kernel) → corrections → operator → uses

>>> import meshlap
>>> V, F = meshlap.shapes.sphere(500, seed=0)
>>> op = meshlap.laplacian(V, F, h=0.01)
>>> op.L.shape
(500, 500)
"""

from . import (
    assembly,
    baselines,
    corrections,
    curvature,
    geometry,
    heat,
    io,
    pipeline,
    reproduce,
    resolution,
    samples,
    shapes,
    smoothing,
    spectral,
    widths,
)
from .builders import laplacian, mesh_laplacian, point_cloud_laplacian, point_cloud_matrices
from .errors import EigenError, MeshError, MeshWarning, OperatorTooLargeError
from .geometry import Geometry, Polygons, topology, validation
from .geometry.mass import face_areas, vertex_mass
from .operator import CORRECTED_TOL, DEFAULT_TOL, MeshLaplacian, truncation_bound
from .widths import default_h

__version__ = "0.1.0"

__all__ = [
    "CORRECTED_TOL",
    "DEFAULT_TOL",
    "EigenError",
    "Geometry",
    "MeshError",
    "MeshLaplacian",
    "MeshWarning",
    "OperatorTooLargeError",
    "Polygons",
    "assembly",
    "baselines",
    "corrections",
    "curvature",
    "default_h",
    "face_areas",
    "geometry",
    "heat",
    "io",
    "laplacian",
    "mesh_laplacian",
    "pipeline",
    "point_cloud_laplacian",
    "point_cloud_matrices",
    "reproduce",
    "resolution",
    "samples",
    "shapes",
    "smoothing",
    "spectral",
    "topology",
    "truncation_bound",
    "validation",
    "vertex_mass",
    "widths",
]
