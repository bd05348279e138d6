"""Stage 1 of the pipeline: what the heat kernel needs of any input.

:class:`Geometry` holds the points, their masses, the intrinsic dimension k, the cells when
there are any and the boundary; normals, tangent frames, neighbour edges and boundary frames
are computed from it on first use and kept (:mod:`meshlap.geometry.frames`). Builders:
:func:`from_mesh` (curves, surfaces, tetrahedra) and :func:`point_cloud_geometry`.

Modules: :mod:`~meshlap.geometry.polygons` (faces of any size), :mod:`~.validation` (input
checks), :mod:`~.mass` (areas, lumped masses), :mod:`~.topology` (mesh diagnostics),
:mod:`~.core` (Geometry and the mesh builders), :mod:`~.pointcloud` (masses of a cloud),
:mod:`~.frames` (normals, frames, boundary).
"""

from . import frames, mass, topology, validation
from .core import (
    Geometry,
    cell_columns,
    check_points,
    from_mesh,
    polyline,
    simplex_volumes,
    spatial_order,
    surface,
    tetrahedra,
)
from .noise import project_to_tangent
from .pointcloud import point_cloud_geometry, point_masses
from .polygons import Polygons

__all__ = [
    "Geometry",
    "Polygons",
    "cell_columns",
    "check_points",
    "frames",
    "from_mesh",
    "mass",
    "point_cloud_geometry",
    "point_masses",
    "polyline",
    "project_to_tangent",
    "simplex_volumes",
    "spatial_order",
    "surface",
    "tetrahedra",
    "topology",
    "validation",
]
