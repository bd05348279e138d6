"""Mesh reading and writing, trimesh-like objects, and saving/loading built operators."""

from pathlib import Path

import igl
import numpy as np
import pytest
import scipy.sparse as sp

import meshlap
from meshlap import io
from meshlap.baselines import cotangent
from meshlap.inputs import read_input

DATA = Path(__file__).parent / "data"

# Quads, a pentagon and triangles with every face-token form, negative (relative) indices,
# comments, texture/normal lines, groups, a continued line and CRLF line ends.
MIXED_OBJ = (
    "# mixed polygons\r\n"
    "mtllib none.mtl\n"
    "o thing\n"
    "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\nv 1.5 1.8 0.25 0.1 0.2 0.3\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
    "g quads\ns off\n"
    "f 1/1/1 2/2/1 5/3/1 4/1/1\n"
    "f 2//1 3//1 \\\n 6//1\n"
    "usemtl red\n"
    "f -6/2 -4/3 -1/1 -2\n"
    "f 4 5 7\n"
    "l 1 2\n"
)


def test_spot_quads_kept_as_quads():
    V, F = io.read_mesh(DATA / "spot-quads.obj")
    Vi, _, _, Fi, _, _ = igl.readOBJ(str(DATA / "spot-quads.obj"))
    assert F.dtype == np.int64 and F.shape == (2928, 4)
    np.testing.assert_array_equal(V, Vi)
    np.testing.assert_array_equal(F, Fi)
    # each quad gives Area/4 to each corner, so the masses add up to the surface area; a
    # non-planar quad's vector area is a little below that of its two fan triangles
    area_fan = igl.doublearea(V, io.read_mesh(DATA / "spot-quads.obj", triangulate=True)[1]).sum() / 2
    total = meshlap.vertex_mass(V, F).sum()
    assert 0.995 * area_fan < total < area_fan


def test_triangle_obj_matches_libigl_exactly():
    V, F = io.read_mesh(DATA / "spot.obj")
    Vi, Fi = igl.read_triangle_mesh(str(DATA / "spot.obj"))
    np.testing.assert_array_equal(V, Vi)
    np.testing.assert_array_equal(F, Fi)


def test_mixed_polygon_obj(tmp_path):
    p = tmp_path / "mixed.obj"
    p.write_bytes(MIXED_OBJ.encode())
    V, F = io.read_mesh(p)
    assert isinstance(F, meshlap.Polygons)
    assert F.sizes.tolist() == [4, 3, 4, 3]
    faces = np.split(F.indices, F.offsets[1:-1])
    assert [f.tolist() for f in faces] == [[0, 1, 4, 3], [1, 2, 5], [1, 3, 6, 5], [3, 4, 6]]
    np.testing.assert_array_equal(V[6], [1.5, 1.8, 0.25])  # colour values after xyz ignored
    tri = io.read_mesh(p, triangulate=True)[1]
    assert tri.shape == (2 + 1 + 2 + 1, 3)
    op = meshlap.laplacian(V, F, h=0.5, correction="none")
    assert op.faces.sizes.tolist() == [4, 3, 4, 3]
    # the operator takes the polygons as they are; its rows annihilate constants
    np.testing.assert_allclose(op.L @ np.ones(7), 0, atol=1e-12)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "index 0 refers to no vertex"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4: face index 4 refers to no vertex"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "index -4 refers to no vertex"),
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", "at least 3 corners"),
        ("v 0 0 x\n", "line 1: bad vertex coordinate"),
        ("v 0 0\n", "needs 3 coordinates"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 a 3\n", "bad face index 'a'"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"),
        ("# empty\n", "no vertices"),
    ],
)
def test_obj_errors_name_the_line(tmp_path, text, message):
    p = tmp_path / "bad.obj"
    p.write_text(text)
    with pytest.raises(meshlap.MeshError, match=message):
        io.read_mesh(p)


def test_off_polygons_and_errors(tmp_path):
    p = tmp_path / "q.off"
    p.write_text("OFF\n# comment\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0.5 0\n"
                 "4 0 1 2 3 255 0 0\n3 1 4 2\n")
    V, F = io.read_mesh(p)
    assert F.sizes.tolist() == [4, 3] and F.indices.tolist() == [0, 1, 2, 3, 1, 4, 2]
    p.write_text("OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")  # counts on the header line
    assert io.read_mesh(p)[1].tolist() == [[0, 1, 2]]
    for text, message in [
        ("COFF\n3 1 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n3 0 1 2\n", "plain OFF"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n", "truncated"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0.5", "q.off: vertex 2 has 1 of its 3 values"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0.5 zero 1\n3 0 1 2\n", "q.off: vertex 2: 'zero' is not a number"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", "refers to vertex 5"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "fewer corners"),
    ]:
        p.write_text(text)
        with pytest.raises(meshlap.MeshError, match=message):
            io.read_mesh(p)


def test_off_faces_over_several_lines_and_binary_off(tmp_path):
    """libigl's inspired_mesh_quads_Smooth.off writes each face's corners one per line (OFF is a
    stream of tokens); pmp-library writes binary OFF little endian without colour counts, where
    Geomview's is big endian with them. All three read as the text file's square."""
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    p = tmp_path / "q.off"
    p.write_text("OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0\n1\n2\n3 0 2\n3\n")
    W, F = io.read_mesh(p)
    assert np.array_equal(W, V) and F.tolist() == [[0, 1, 2], [0, 2, 3]]
    for order, colours in ((">", True), ("<", False)):
        faces = [np.r_[3, f, [0] if colours else []] for f in ([0, 1, 2], [0, 2, 3])]
        body = (np.array([4, 2, 0], f"{order}i4").tobytes() + V.astype(f"{order}f4").tobytes()
                + np.concatenate(faces).astype(f"{order}i4").tobytes())
        p.write_bytes(b"OFF BINARY\n" + body)
        W, F = io.read_mesh(p)
        assert np.array_equal(W, V) and F.tolist() == [[0, 1, 2], [0, 2, 3]], order
        for cut in (b"OFF BINARY\n" + body[:-6], b"OFF BINARY"):
            p.write_bytes(cut)
            with pytest.raises(meshlap.MeshError, match="binary OFF file whose counts and faces do not fit"):
                io.read_mesh(p)


def _pcd_header(fields, size, kind, count, n, data, height=1):
    return (f"# .PCD v0.7\nVERSION 0.7\nFIELDS {' '.join(fields)}\nSIZE {' '.join(map(str, size))}\n"
            f"TYPE {' '.join(kind)}\nCOUNT {' '.join(map(str, count))}\nWIDTH {n // height}\n"
            f"HEIGHT {height}\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n").encode()


def test_pcd_point_clouds_ascii_binary_and_compressed(tmp_path):
    """PCL's PCD: ascii, binary and binary_compressed (LZF, field after field); fields besides
    x, y, z read past (a 3-count normal, a 16-bit label); NaN rows (an organized cloud's pixels
    without a return) left out. The compressed file was written by pypcd4 with liblzf's
    compressor (tests/data/README.md)."""
    j, i = np.mgrid[0:30, 0:40]
    x, y = 0.01 * i.ravel(), 0.01 * j.ravel()
    P = np.column_stack([x, y, 0.5 + 0.25 * x]).astype(np.float32)
    P[::7] = np.nan
    want = P[~np.isnan(P).any(axis=1)].astype(np.float64)
    got = io.read_points(DATA / "grid_compressed.pcd")
    assert got.shape == (1028, 3) and np.array_equal(got, want)
    rng = np.random.default_rng(0)
    n = len(P)
    normal, label = rng.normal(size=(n, 3)).astype(np.float32), np.arange(n, dtype=np.int16)
    fields, size, kind, count = ["normal", "x", "y", "z", "label"], [4, 4, 4, 4, 2], "FFFFI", [3, 1, 1, 1, 1]
    p = tmp_path / "c.pcd"
    record = np.dtype([("n", "<f4", (3,)), ("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("l", "<i2")])
    body = np.zeros(n, record)
    body["n"], body["x"], body["y"], body["z"], body["l"] = normal, P[:, 0], P[:, 1], P[:, 2], label
    p.write_bytes(_pcd_header(fields, size, kind, count, n, "binary", height=30) + body.tobytes())
    assert np.array_equal(io.read_points(p), want)
    rows = "\n".join(" ".join(f"{v:.9g}" for v in (*nn, a, b, c, ll))
                     for nn, (a, b, c), ll in zip(normal, P, label, strict=True))
    p.write_bytes(_pcd_header(fields, size, kind, count, n, "ascii") + rows.encode())
    assert np.allclose(io.read_points(p), want, rtol=1e-7)
    op = meshlap.point_cloud_laplacian(str(DATA / "grid_compressed.pcd"))  # a path, as the CLI reads it
    assert op.n_vertices == 1028
    # what is wrong is said, not crashed on
    cases = [
        (_pcd_header(fields, size, kind, count, n, "binary") + body.tobytes()[:-10], "cut short"),
        (_pcd_header(fields, size, kind, count, n, "binary_lzma") + body.tobytes(), "binary_lzma"),
        (_pcd_header(["a", "b", "c"], [4] * 3, "FFF", [1] * 3, n, "binary") + body.tobytes(), "x, y and z"),
        ((DATA / "grid_compressed.pcd").read_bytes()[:-40], "does not decompress"),
        (b"VERSION 0.7\nFIELDS x y z\n", "no DATA line"),
    ]
    for data, message in cases:
        p.write_bytes(data)
        with pytest.raises(meshlap.MeshError, match=message):
            io.read_points(p)


def test_ply_meshes_read_their_vertices_or_name_the_bad_row(tmp_path):
    """libigl reads a PLY mesh's malformed ASCII vertex as zeros without a word (then its faces as
    garbage indices); meshlap reads the vertices itself and names the row. Well-formed PLY meshes,
    ASCII and big-endian binary with extra properties, read as written."""
    V, F = meshlap.shapes.sphere(200, seed=0)
    head = (f"ply\nformat ascii 1.0\nelement vertex {len(V)}\nproperty double x\nproperty double y\n"
            f"property double z\nproperty double nx\nproperty double ny\nproperty double nz\n"
            f"element face {len(F)}\nproperty list uchar uint vertex_indices\nend_header\n")
    rows = [" ".join(repr(float(x)) for x in v) + " 0 0 1" for v in V]
    faces = "".join(f"3 {a} {b} {c}\n" for a, b, c in F.tolist())
    (tmp_path / "a.ply").write_text(head + "\n".join(rows) + "\n" + faces)
    Vr, Fr = io.read_mesh(tmp_path / "a.ply")
    assert np.array_equal(Vr, V) and np.array_equal(Fr, F)
    rows[5] = "0.1 zero 0.3 0 0 1"
    (tmp_path / "bad.ply").write_text(head + "\n".join(rows) + "\n" + faces)
    with pytest.raises(meshlap.MeshError, match="bad.ply: vertex 5: 'zero' is not a number"):
        io.read_mesh(tmp_path / "bad.ply")
    vertex = np.zeros(len(V), dtype=[("x", ">f8"), ("y", ">f8"), ("z", ">f8"), ("red", "u1")])
    vertex["x"], vertex["y"], vertex["z"] = V.T
    face = np.zeros(len(F), dtype=[("n", "u1"), ("i", ">i4", (3,))])
    face["n"], face["i"] = 3, F
    head = (f"ply\nformat binary_big_endian 1.0\nelement vertex {len(V)}\nproperty double x\n"
            "property double y\nproperty double z\nproperty uchar red\n"
            f"element face {len(F)}\nproperty list uchar int vertex_indices\nend_header\n")
    (tmp_path / "be.ply").write_bytes(head.encode() + vertex.tobytes() + face.tobytes())
    Vr, Fr = io.read_mesh(tmp_path / "be.ply")
    assert np.array_equal(Vr, V) and np.array_equal(Fr, F)


def test_ply_triangle_strips_are_read_as_their_triangles(tmp_path):
    """Some scans (igea, from common-3d-test-models) store triangle strips in a ``tristrips``
    element, -1 between strips; meshlap said "a PLY file without faces" (trimesh and pyvista read
    no faces either). A 5 × 4 grid in row strips, two joined by repeated corners, reads as the grid's
    24 triangles, every one turning the same way, ASCII and binary alike."""
    nx, ny = 5, 4
    X, Y = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float))
    V = np.column_stack([X.ravel(), Y.ravel(), np.zeros(nx * ny)])
    strips = [np.column_stack([r * nx + np.arange(nx), (r + 1) * nx + np.arange(nx)]).ravel()
              for r in range(ny - 1)]
    # the last two rows joined into one strip by repeated corners (4 empty triangles), the first apart
    flat = np.r_[strips[0], -1, strips[1], strips[1][-1], strips[2][0], strips[2]]
    head = (f"element vertex {len(V)}\nproperty float x\nproperty float y\nproperty float z\n"
            "element tristrips 1\nproperty list int int vertex_indices\nend_header\n")
    rows = "".join(f"{x} {y} {z}\n" for x, y, z in V)
    (tmp_path / "a.ply").write_text("ply\nformat ascii 1.0\n" + head + rows + f"{len(flat)} "
                                    + " ".join(map(str, flat)) + "\n")
    body = V.astype("<f4").tobytes() + np.r_[len(flat), flat].astype("<i4").tobytes()
    (tmp_path / "b.ply").write_bytes(("ply\nformat binary_little_endian 1.0\n" + head).encode() + body)
    corner = np.arange(nx * ny).reshape(ny, nx)[:-1, :-1].ravel()
    grid = np.vstack([np.column_stack([corner, corner + nx, corner + 1]),
                      np.column_stack([corner + 1, corner + nx, corner + nx + 1])])
    cells = {tuple(sorted(t)) for t in grid.tolist()}
    for name in ("a.ply", "b.ply"):
        Vr, F = io.read_mesh(tmp_path / name)
        assert np.array_equal(Vr, V) and F.shape == (24, 3)
        assert {tuple(sorted(t)) for t in F.tolist()} == cells
        turn = np.cross(Vr[F[:, 1]] - Vr[F[:, 0]], Vr[F[:, 2]] - Vr[F[:, 0]])[:, 2]
        assert np.all(turn < 0) or np.all(turn > 0)
    second = np.r_[strips[1], strips[1][-1], strips[2][0], strips[2]]  # the same strips, one a row
    rows_of_strips = head.replace("element tristrips 1", "element tristrips 2")
    lists = "".join(f"{len(s)} " + " ".join(map(str, s)) + "\n" for s in (strips[0], second))
    (tmp_path / "d.ply").write_text("ply\nformat ascii 1.0\n" + rows_of_strips + rows + lists)
    assert {tuple(sorted(t)) for t in io.read_mesh(tmp_path / "d.ply")[1].tolist()} == cells
    (tmp_path / "c.ply").write_text("ply\nformat ascii 1.0\n" + head.split("element tristrips")[0]
                                    + "end_header\n" + rows)
    with pytest.raises(meshlap.MeshError, match="c.ply: a PLY file without faces"):
        io.read_mesh(tmp_path / "c.ply")


def test_mni_surfaces_are_read_as_vtk_reads_them(tmp_path):
    """MNI's and CIVET's brain surfaces are ``.obj`` files of another format (``P`` and a stream of
    numbers: pyvista's mni-surface-mesh.obj); meshlap read no points from them. A sphere written
    in it reads back exactly (points, triangles; one colour per point), and mixed polygons (one
    colour) as polygons; ``laplacian`` and ``read_points`` take the path."""
    V, F = meshlap.shapes.sphere(200, seed=0)
    normals = V / np.linalg.norm(V, axis=1, keepdims=True)
    words = ["P 0.3 0.3 0.4 10 1", len(V), *V.ravel(), *normals.ravel(), len(F), 2, *np.ones(4 * len(V)),
             *range(3, 3 * len(F) + 1, 3), *F.ravel()]
    (tmp_path / "s.obj").write_text(" ".join(map(str, words)))
    Vr, Fr = io.read_mesh(tmp_path / "s.obj")
    assert np.array_equal(Vr, V) and np.array_equal(Fr, F)
    assert np.array_equal(io.read_points(tmp_path / "s.obj"), V)
    assert meshlap.laplacian(tmp_path / "s.obj").n_vertices == len(V)
    quad = "P 0 0 0 1 1 5 0 0 0 1 0 0 1 1 0 0 1 0 2 0 -1 " + "0 0 1 " * 5 + "2 0 1 1 1 1 4 7 0 1 2 3 1 4 2"
    (tmp_path / "q.obj").write_text(quad)
    V2, F2 = io.read_mesh(tmp_path / "q.obj")
    assert V2.shape == (5, 3) and isinstance(F2, meshlap.Polygons) and F2.sizes.tolist() == [4, 3]


def test_freesurfer_and_gifti_surfaces_are_read(tmp_path):
    """Brain surfaces, LaPy's main inputs: FreeSurfer's (``lh.pial``: no suffix tells the format;
    meshlap said "unknown mesh format") are told by their first bytes and read as nibabel writes
    them, with one more blank line too; GIfTI's ``.surf.gii`` through nibabel. A cut file, an old
    quad surface and a GIfTI file of data without its surface each say what they are."""
    nibabel = pytest.importorskip("nibabel", reason="nibabel absent (pip install nibabel)")
    from nibabel.freesurfer import write_geometry
    from nibabel.gifti import GiftiDataArray, GiftiImage

    V, F = meshlap.shapes.sphere(300, seed=0)
    write_geometry(str(tmp_path / "lh.sphere"), V, F, create_stamp="created by meshlap's tests")
    Vr, Fr = io.read_mesh(tmp_path / "lh.sphere")
    assert np.array_equal(Vr, V.astype(np.float32)) and np.array_equal(Fr, F)
    P, cells, k = read_input(tmp_path / "lh.sphere")
    assert k == 2 and np.array_equal(P, Vr) and np.array_equal(cells, F)
    lam = meshlap.spectral.eigs(meshlap.laplacian(tmp_path / "lh.sphere"), 4)[0]
    assert np.allclose(lam[1:], 2.0, rtol=0.02)  # the unit sphere's l = 1
    data = (tmp_path / "lh.sphere").read_bytes()
    cut = data.index(b"\n\n") + 2
    (tmp_path / "rh.blank").write_bytes(data[:cut] + b"\n" + data[cut:])
    assert np.array_equal(io.read_mesh(tmp_path / "rh.blank")[1], F)
    (tmp_path / "lh.cut").write_bytes(data[:len(data) // 2])
    with pytest.raises(meshlap.MeshError, match="lh.cut: the file ends before its 300 vertices and 596 tri"):
        io.read_mesh(tmp_path / "lh.cut")
    (tmp_path / "lh.quad").write_bytes(b"\xff\xff\xff" + data[3:])
    with pytest.raises(meshlap.MeshError, match="lh.quad: a FreeSurfer quad surface"):
        read_input(tmp_path / "lh.quad")
    surf = GiftiImage(darrays=[GiftiDataArray(V.astype(np.float32), intent="NIFTI_INTENT_POINTSET"),
                               GiftiDataArray(F.astype(np.int32), intent="NIFTI_INTENT_TRIANGLE")])
    nibabel.save(surf, str(tmp_path / "lh.surf.gii"))
    P, cells, k = read_input(tmp_path / "lh.surf.gii")
    assert k == 2 and np.array_equal(P, Vr) and np.array_equal(cells.as_array(), F)
    thickness = GiftiDataArray(V[:, 0].astype(np.float32), intent="NIFTI_INTENT_SHAPE")
    nibabel.save(GiftiImage(darrays=[thickness]), str(tmp_path / "lh.thickness.shape.gii"))
    with pytest.raises(meshlap.MeshError, match="without a point set"):
        read_input(tmp_path / "lh.thickness.shape.gii")


def test_files_cut_short_end_in_one_line_naming_where(tmp_path):
    """A PLY mesh cut inside its faces aborted the whole process in libigl's reader (a double free);
    meshlap reads PLY itself. Every cut names where the file ends or which row is short."""
    V, F = meshlap.shapes.sphere(60, seed=0)
    io.write_mesh(tmp_path / "a.ply", V, F)  # ASCII
    vertex = np.zeros(len(V), dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4")])
    vertex["x"], vertex["y"], vertex["z"] = V.T
    face = np.zeros(len(F), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    face["n"], face["i"] = 3, F
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(V)}\nproperty float x\n"
            f"property float y\nproperty float z\nelement face {len(F)}\n"
            "property list uchar int vertex_indices\nend_header\n")
    (tmp_path / "b.ply").write_bytes(head.encode() + vertex.tobytes() + face.tobytes())
    assert np.array_equal(io.read_mesh(tmp_path / "b.ply")[1], F)
    for name, message in (("a.ply", "the file ends at face"), ("b.ply", "the file ends inside face")):
        data = (tmp_path / name).read_bytes()
        (tmp_path / f"cut-{name}").write_bytes(data[:int(0.83 * len(data))])
        with pytest.raises(meshlap.MeshError, match=f"cut-{name}: {message}"):
            io.read_mesh(tmp_path / f"cut-{name}")
    (tmp_path / "v.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1\n")  # no faces: a point cloud, cut
    with pytest.raises(meshlap.MeshError, match="v.obj: vertex 2 has 2 of its 3 values"):
        io.read_points(tmp_path / "v.obj")
    (tmp_path / "t.node").write_text("3 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1\n")
    (tmp_path / "t.ele").write_text("1 4 0\n1 1 2 3 3\n")
    with pytest.raises(meshlap.MeshError, match="t.node: row 2 has 3 of its 4 values"):
        io.read_tetrahedra(tmp_path / "t.ele")


def test_missing_file_and_unknown_format(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such mesh file"):
        io.read_mesh(tmp_path / "nope.obj")
    (tmp_path / "m.xyz").write_text("1 2 3\n")
    with pytest.raises(meshlap.MeshError, match="unknown mesh format '.xyz'"):
        io.read_mesh(tmp_path / "m.xyz")
    (tmp_path / "m.ply").write_text("not a ply\n")
    with pytest.raises(meshlap.MeshError, match="m.ply"):
        io.read_mesh(tmp_path / "m.ply")
    # trimesh's empty.stl: libigl reports "Failed to open file" for a file it opened
    (tmp_path / "empty.stl").write_text("solid Empty\nendsolid Empty")
    with pytest.raises(meshlap.MeshError, match="empty.stl: an ASCII STL file without facets"):
        io.read_mesh(tmp_path / "empty.stl")


@pytest.mark.parametrize(("suffix", "atol"), [(".obj", 0), (".off", 0), (".ply", 1e-6), (".stl", 1e-6)])
def test_write_read_round_trip(tmp_path, suffix, atol):
    V, F = meshlap.shapes.sphere(300, seed=2)
    V2, F2 = io.read_mesh(io.write_mesh(tmp_path / f"s{suffix}", V, F))
    assert V2.shape == V.shape and F2.shape == F.shape
    if suffix == ".stl":
        # STL has no shared vertices: they were merged back, in another order. Compare the
        # triangles as sets of corner positions.
        key = lambda V_, F_: np.sort(np.round(V_[F_], 5).reshape(len(F_), -1), axis=0)  # noqa: E731
        np.testing.assert_allclose(key(V2, F2), key(V, F), atol=1e-5)
        assert meshlap.vertex_mass(V2, F2).sum() == pytest.approx(meshlap.vertex_mass(V, F).sum(), rel=1e-6)
    else:
        np.testing.assert_allclose(V2, V, rtol=0, atol=atol)
        np.testing.assert_array_equal(F2, F)


def test_polygon_round_trip_and_triangle_only_formats(tmp_path):
    p = tmp_path / "mixed.obj"
    p.write_text(MIXED_OBJ)
    V, F = io.read_mesh(p)
    for suffix in (".obj", ".off"):
        V2, F2 = io.read_mesh(io.write_mesh(tmp_path / f"again{suffix}", V, F))
        np.testing.assert_array_equal(V2, V)
        np.testing.assert_array_equal(F2.indices, F.indices)
        np.testing.assert_array_equal(F2.offsets, F.offsets)
    with pytest.raises(meshlap.MeshError, match="triangles only"):
        io.write_mesh(tmp_path / "x.stl", V, F)


def test_as_mesh_accepts_trimesh_like_objects_pairs_and_paths():
    V, F = meshlap.shapes.sphere(100, seed=0)

    class FakeTrimesh:  # what trimesh.Trimesh offers: TrackedArray subclasses of ndarray
        vertices = V.astype(np.float32)
        faces = F.astype(np.int32)

    class FakeOpen3D:
        vertices = V.tolist()
        triangles = F.tolist()

    for mesh in (FakeTrimesh(), FakeOpen3D(), (V, F)):
        V2, F2 = io.as_mesh(mesh)
        assert V2.dtype == np.float64 and F2.dtype == np.int64
        np.testing.assert_allclose(V2, V, atol=1e-6)
        np.testing.assert_array_equal(F2, F)
    assert io.as_mesh(DATA / "spot.obj")[0].shape == (2930, 3)
    with pytest.raises(meshlap.MeshError, match="cannot read a mesh from a dict"):
        io.as_mesh({"V": V})

    class Broken:
        vertices = V
        faces = F + 100

    with pytest.raises(meshlap.MeshError, match="mesh faces refers to vertex"):
        io.as_mesh(Broken())


def test_save_load_operator_bit_for_bit(tmp_path):
    V, F = io.read_mesh(DATA / "spot-quads.obj")
    op = meshlap.laplacian(V, F, h=0.004, tol=1e-6, correction="none")
    path = io.save_operator(tmp_path / "spot", op)
    assert path.name == "spot.npz"
    back = io.load_operator(path)
    assert isinstance(back, io.SavedLaplacian)
    for a in ("data", "indices", "indptr"):
        np.testing.assert_array_equal(getattr(back.L, a), getattr(op.L, a))
    assert (back.h, back.tol, back.radius, back.h_auto) == (op.h, op.tol, op.radius, False)
    np.testing.assert_array_equal(back.mass, op.mass)
    np.testing.assert_array_equal(back.V, op.V)
    np.testing.assert_array_equal(back.faces.offsets, op.faces.offsets)
    f = np.sin(3 * V)
    np.testing.assert_array_equal(back @ f, op @ f)
    assert abs(back.S - op.S).max() == 0 and abs(back.M - op.M).max() == 0
    assert back.nbytes == op.nbytes
    # scipy reads the same file as a plain CSR matrix
    assert abs(sp.load_npz(path) - op.L).max() == 0


def test_save_load_variants(tmp_path):
    V, F = meshlap.shapes.sphere(400, seed=1)
    op32 = meshlap.laplacian(V, F, h=0.01, dtype=np.float32, correction="none")
    back = io.load_operator(io.save_operator(tmp_path / "op32.npz", op32, mesh=False, compress=True))
    assert back.L.dtype == np.float32 and not hasattr(back, "V") and not hasattr(back, "faces")
    assert back.h_auto is False and back.h == 0.01
    cot = io.load_operator(io.save_operator(tmp_path / "cot.npz", cotangent(V, F)))
    assert cot.name == "COT" and cot.h is None
    np.testing.assert_allclose(cot @ V, cotangent(V, F) @ V, rtol=1e-12, atol=1e-12)
    auto = io.load_operator(io.save_operator(tmp_path / "auto.npz", meshlap.laplacian(V, F,
            correction="none")))
    assert auto.h_auto is True and auto.h == pytest.approx(meshlap.default_h(V, F))


def test_save_load_errors(tmp_path):
    V, F = meshlap.shapes.sphere(100, seed=0)
    with pytest.raises(meshlap.MeshError, match="needs an operator"):
        io.save_operator(tmp_path / "x.npz", V)
    with pytest.raises(FileNotFoundError):
        io.load_operator(tmp_path / "missing.npz")
    np.savez(tmp_path / "other.npz", a=np.arange(3))
    with pytest.raises(meshlap.MeshError, match="not an operator saved by meshlap"):
        io.load_operator(tmp_path / "other.npz")
    (tmp_path / "text.npz").write_text("hello")
    with pytest.raises(meshlap.MeshError, match="not an .npz file"):
        io.load_operator(tmp_path / "text.npz")


def test_loaded_operators_work_with_the_spectral_solver(tmp_path):
    from meshlap.spectral import eigs

    V, F = meshlap.shapes.sphere(1500, seed=0)
    op = meshlap.laplacian(V, F, h=0.005, correction="none")
    lam = eigs(op, 6, method="lobpcg")[0]
    for mesh in (True, False):  # without the mesh, LOBPCG runs without the cotangent preconditioner
        back = io.load_operator(io.save_operator(tmp_path / f"op{mesh}.npz", op, mesh=mesh))
        assert hasattr(back, "V") is mesh
        np.testing.assert_allclose(eigs(back, 6, method="lobpcg")[0], lam, rtol=1e-6, atol=1e-9)


# -- point clouds, polylines, tetrahedra (issue 13) ----------------------------------------------
def test_read_points_all_formats(tmp_path):
    P = np.random.default_rng(0).normal(size=(50, 3))
    np.save(tmp_path / "p.npy", P)
    np.savetxt(tmp_path / "p.xyz", np.column_stack([P, np.ones(50)]))  # a 4th column: intensity
    (tmp_path / "p.csv").write_text("x,y,z\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in P))
    head = "ply\nformat {}\nelement vertex 50\nproperty float x\nproperty float y\nproperty float z\n"
    (tmp_path / "a.ply").write_text(head.format("ascii 1.0") + "end_header\n"
                                    + "\n".join(" ".join(map(str, r)) for r in P.astype(np.float32)))
    (tmp_path / "b.ply").write_bytes((head.format("binary_little_endian 1.0") + "end_header\n").encode()
                                     + P.astype("<f4").tobytes())
    for name in ("p.npy", "p.xyz", "p.csv"):
        assert np.allclose(meshlap.io.read_points(tmp_path / name), P, rtol=1e-15)
    for name in ("a.ply", "b.ply"):
        assert np.allclose(meshlap.io.read_points(tmp_path / name), P, rtol=1e-6)
    assert meshlap.io.read_points(tmp_path / "p.xyz", columns=range(4)).shape == (50, 4)
    V = meshlap.io.read_points("tests/data/spot.obj")
    assert V.shape == (2930, 3)
    (tmp_path / "bad.csv").write_text("1,2,3\n4,five,6\n")
    with pytest.raises(meshlap.MeshError, match="not a number"):
        meshlap.io.read_points(tmp_path / "bad.csv")
    (tmp_path / "p.bin").write_bytes(b"\0\0\0\0")
    with pytest.raises(meshlap.MeshError, match="unknown point cloud format"):
        meshlap.io.read_points(tmp_path / "p.bin")


def test_read_polyline_and_tetrahedra(tmp_path):
    V, E, _ = meshlap.samples.circle(40, d=3)
    (tmp_path / "c.obj").write_text("".join(f"v {x} {y} {z}\n" for x, y, z in V)
                                    + "l " + " ".join(str(i + 1) for i in range(40)) + " 1\n")
    V2, E2 = meshlap.io.read_polyline(tmp_path / "c.obj")
    assert np.allclose(V2, V) and np.array_equal(E2, E)
    V, T = meshlap.samples.cube_tetrahedra(2)
    (tmp_path / "c.node").write_text(f"{len(V)} 3 0 0\n" + "".join(f"{i + 1} {x} {y} {z}\n"
                                                                   for i, (x, y, z) in enumerate(V)))
    (tmp_path / "c.ele").write_text(f"{len(T)} 4 0\n" + "".join(f"{i + 1} " + " ".join(str(v + 1) for v in t)
                                                                + "\n" for i, t in enumerate(T)))
    V3, T3 = meshlap.io.read_tetrahedra(tmp_path / "c.node")
    assert np.allclose(V3, V) and np.array_equal(T3, T)
    assert meshlap.laplacian(V3, T3, k=3).mass.sum() == pytest.approx(1.0)
