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
    descriptors,
    fem,
    geodesics,
    geometry,
    gradients,
    heat,
    inputs,
    io,
    pipeline,
    plot,
    policy,
    reproduce,
    samples,
    shapes,
    smoothing,
    solve,
    spectral,
    tuned,
    widths,
)
from .assembly import truncation_bound
from .builders import (
    laplacian,
    mesh_laplacian,
    point_cloud_laplacian,
    point_cloud_matrices,
    pointwise_laplacian,
)
from .errors import EigenError, MeshError, MeshWarning, OperatorTooLargeError
from .geodesics import HeatDistance, geodesic_distance
from .geometry import Geometry, Polygons, topology, validation
from .geometry.mass import face_areas, vertex_mass
from .operator import CORRECTED_TOL, DEFAULT_TOL, MeshLaplacian
from .solve import harmonic, poisson
from .widths import default_h

__version__ = "0.1.0"

__all__ = [
    "CORRECTED_TOL",
    "DEFAULT_TOL",
    "EigenError",
    "Geometry",
    "HeatDistance",
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
    "descriptors",
    "face_areas",
    "fem",
    "geodesic_distance",
    "geodesics",
    "geometry",
    "gradients",
    "harmonic",
    "heat",
    "inputs",
    "io",
    "laplacian",
    "mesh_laplacian",
    "pipeline",
    "plot",
    "policy",
    "point_cloud_laplacian",
    "point_cloud_matrices",
    "pointwise_laplacian",
    "poisson",
    "reproduce",
    "samples",
    "shapes",
    "smoothing",
    "solve",
    "spectral",
    "topology",
    "truncation_bound",
    "tuned",
    "validation",
    "vertex_mass",
    "widths",
]
