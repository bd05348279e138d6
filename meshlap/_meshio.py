"""Files read through meshio (Gmsh ``.msh``, VTU, XDMF, ...): the points and cells meshlap takes.

meshio also reads a file's data sections, and refuses the whole file where they do not match its
cells: libigl's ``writeMSH`` stores its element data for the tetrahedra alone beside triangles
too (libigl's tutorial ``hand.msh``), and meshio raised "Incompatible cell data". meshlap reads
no data, so a Gmsh file meshio refuses is read once more without its data sections.
"""

from __future__ import annotations

import contextlib
import io
import re
import tempfile
from pathlib import Path
from typing import Any

from .errors import MeshError, first_line

__all__ = ["read"]

# a Gmsh section of data on nodes or elements, from its opening line to its closing one (in a
# binary file the closing key follows the last value without a line break)
_DATA = re.compile(rb"(?<=\n)\$(NodeData|ElementData|ElementNodeData)\r?\n.*?\$End\1\r?\n?", re.DOTALL)


def _read(meshio: Any, path: Path) -> Any:
    said = io.StringIO()
    try:  # on a bad file meshio prints its reasons and calls sys.exit; keep them for the message
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            return meshio.read(path)
    except (Exception, SystemExit) as exc:  # meshio's ReadError, ValueError, KeyError, exit, ...
        reason = (said.getvalue().strip().splitlines() or [first_line(exc)])[0]
        raise MeshError(f"{path.name}: meshio could not read it ({reason})") from None


def read(path: Path) -> Any:
    """The ``meshio.Mesh`` of ``path``; a :class:`~meshlap.errors.MeshError` that names meshio's
    reason where it cannot read it, an ``ImportError`` where meshio is not installed.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "t.msh"
    >>> _ = p.write_text("$MeshFormat\\n2.2 0 8\\n$EndMeshFormat\\n$Nodes\\n3\\n1 0 0 0\\n2 1 0 0\\n"
    ...                  "3 0 1 0\\n$EndNodes\\n$Elements\\n1\\n1 2 0 1 2 3\\n$EndElements\\n")
    >>> read(p).cells_dict["triangle"].tolist()
    [[0, 1, 2]]
    """
    import meshio

    try:
        return _read(meshio, path)
    except MeshError as refused:
        data = path.read_bytes() if path.suffix.lower() == ".msh" else b""
        stripped = _DATA.sub(b"", data)
        if stripped == data:  # not Gmsh, or no data sections to leave out
            raise
        with tempfile.TemporaryDirectory() as folder:
            copy = Path(folder) / path.name
            copy.write_bytes(stripped)
            try:
                return _read(meshio, copy)
            except MeshError:
                raise refused from None  # meshio's reason on the file as given
