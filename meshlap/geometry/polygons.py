"""Faces of any size in one flat form: the data type every geometry module imports."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import MeshError

__all__ = ["Polygons"]


@dataclass(frozen=True)
class Polygons:
    """Faces of any size, stored flat: face ``i`` is ``indices[offsets[i]:offsets[i+1]]``.

    Triangle and quad arrays, and lists of mixed polygons, all become this one form.
    """

    indices: np.ndarray  # int64, all corners of all faces
    offsets: np.ndarray  # int64, len = n_faces + 1

    @property
    def n_faces(self) -> int:
        return len(self.offsets) - 1

    @property
    def sizes(self) -> np.ndarray:
        """Number of corners #t of each face."""
        return np.diff(self.offsets)

    @property
    def uniform_size(self) -> int | None:
        """The common face size, or None for a mix of sizes."""
        s = self.sizes
        if len(s) and np.all(s == s[0]):
            return int(s[0])
        return None

    def as_array(self) -> np.ndarray:
        """The faces as an (m, k) array; only for meshes whose faces share one size."""
        k = self.uniform_size
        if k is None:
            raise MeshError("faces have mixed sizes; they cannot form one (m, k) array")
        return self.indices.reshape(-1, k)

    def triangles(self) -> np.ndarray:
        """A fan triangulation, (m_tri, 3) int64, e.g. for libigl routines and plots."""
        sizes = self.sizes
        if self.uniform_size == 3:
            return self.indices.reshape(-1, 3)
        n_tri = sizes - 2
        face_of_tri = np.repeat(np.arange(self.n_faces), n_tri)
        # corner k of the fan within its face: 1, 2, ..., size-2
        k = np.arange(n_tri.sum()) - np.repeat(np.cumsum(n_tri) - n_tri, n_tri) + 1
        first = self.offsets[:-1][face_of_tri]
        return np.stack(
            [self.indices[first], self.indices[first + k], self.indices[first + k + 1]], axis=1
        )

    def edges(self) -> np.ndarray:
        """Directed face edges (corner i to corner i+1), (sum #t, 2) int64."""
        nxt = np.arange(1, len(self.indices) + 1)
        last = self.offsets[1:] - 1
        nxt[last] = self.offsets[:-1]
        return np.stack([self.indices, self.indices[nxt]], axis=1)
