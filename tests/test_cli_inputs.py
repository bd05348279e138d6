"""The ``meshlap`` command on point clouds and tetrahedral meshes (issue 21)."""

import re

import numpy as np
import pytest
from test_cli import fails, run

import meshlap
from meshlap.inputs import read_input


def write_tetgen(stem, V, T):
    stem.with_suffix(".node").write_text(f"{len(V)} 3 0 0\n" + "".join(
        f"{i + 1} {x!r} {y!r} {z!r}\n" for i, (x, y, z) in enumerate(V.tolist())))
    stem.with_suffix(".ele").write_text(f"{len(T)} 4 0\n" + "".join(
        f"{i + 1} " + " ".join(str(v + 1) for v in t) + "\n" for i, t in enumerate(T.tolist())))
    return stem.with_suffix(".ele")


def write_ply_cloud(path, P):
    head = f"ply\nformat binary_little_endian 1.0\nelement vertex {len(P)}\n" + "".join(
        f"property double {c}\n" for c in "xyz") + "end_header\n"
    path.write_bytes(head.encode() + P.astype("<f8").tobytes())
    return path


def eigenvalues(out):
    rows = [line.split() for line in out.splitlines()]
    return np.array([float(r[1]) for r in rows if len(r) == 2 and r[0].isdigit()])


@pytest.fixture(scope="module")
def cloud(tmp_path_factory):
    P = meshlap.samples.sphere_points(1000)
    return write_ply_cloud(tmp_path_factory.mktemp("cloud") / "sphere.ply", P)


@pytest.fixture(scope="module")
def tets(tmp_path_factory):
    return write_tetgen(tmp_path_factory.mktemp("tets") / "cube", *meshlap.samples.cube_tetrahedra(6))


def test_eigs_of_a_ply_point_cloud(capsys, cloud, tmp_path):
    code, out, err = run(capsys, "eigs", cloud, "-k", "5", "--png", tmp_path / "modes.png")
    assert code == 0, err
    lam = eigenvalues(out)
    # the unit sphere: 0, then 2 three times
    assert lam[0] == 0 and np.allclose(lam[1:4], 2, rtol=0.03) and lam[4] > 5
    ref = meshlap.spectral.eigs(meshlap.point_cloud_laplacian(meshlap.samples.sphere_points(1000)), 5)[0]
    np.testing.assert_allclose(lam[1:], ref[1:], rtol=1e-5)
    assert (tmp_path / "modes.png").stat().st_size > 10_000


def test_eigs_of_tetrahedra_tetgen_and_meshio(capsys, tets, tmp_path):
    code, out, _ = run(capsys, "eigs", tets, "-k", "4")
    assert code == 0
    lam = eigenvalues(out)
    V, T = meshlap.samples.cube_tetrahedra(6)
    ref = meshlap.spectral.eigs(meshlap.laplacian(V, T, k=3), 4)[0]
    np.testing.assert_allclose(lam[1:], ref[1:], rtol=1e-5)
    # the unit cube's threefold first Neumann eigenvalue π²: on 7³ vertices within 7.1% (measured)
    assert np.abs(lam[1:4] / np.pi**2 - 1).max() < 0.1
    meshio = pytest.importorskip("meshio")
    for suffix in (".vtk", ".vtu", ".msh"):
        path = tmp_path / f"cube{suffix}"
        options = {"file_format": "gmsh22"} if suffix == ".msh" else {}
        meshio.write(path, meshio.Mesh(V, [("tetra", T)]), **options)
        code, out, _ = run(capsys, "eigs", path, "-k", "4")
        assert code == 0 and np.allclose(eigenvalues(out), lam, rtol=1e-5, atol=1e-12), suffix


def _gmsh22(path, V, T, binary):
    # a Gmsh 2.2 file as libigl's writeMSH writes it: the hull's triangles and the tetrahedra, and
    # element data for the tetrahedra alone, which meshio refuses ("Incompatible cell data")
    import struct

    tri = meshlap.inputs.boundary_triangles(T)
    blocks = [(2, tri), (4, T)]
    out = [b"$MeshFormat\n", b"2.2 %d 8\n" % binary]
    if binary:
        out.append(struct.pack("<i", 1) + b"\n")
    out.append(b"$EndMeshFormat\n$Nodes\n%d\n" % len(V))
    if binary:
        out.append(b"".join(struct.pack("<i3d", i + 1, *p) for i, p in enumerate(V)) + b"\n")
    else:
        out += [b"%d %r %r %r\n" % (i + 1, *p) for i, p in enumerate(V.tolist())]
    out.append(b"$EndNodes\n$Elements\n%d\n" % (len(tri) + len(T)))
    number = 0
    for kind, cells in blocks:
        if binary:
            out.append(struct.pack("<3i", kind, len(cells), 2))
        for c in cells:
            number += 1
            fields = [number] + ([] if binary else [kind, 2]) + [1, 1] + [int(x) + 1 for x in c]
            row = struct.pack(f"<{len(fields)}i", *fields) if binary else b" ".join(b"%d" % x for x in fields)
            out.append(row if binary else row + b"\n")
    head = b"$EndElements\n$ElementData\n1\n\"E\"\n1\n0.0\n3\n0\n1\n%d\n" % len(T)
    out.append((b"\n" if binary else b"") + head)
    if binary:  # numbered from 1, as libigl numbers them
        out.append(b"".join(struct.pack("<id", 1 + i, 0.5) for i in range(len(T))) + b"$EndElementData\n")
    else:
        out += [b"%d 0.5\n" % (1 + i) for i in range(len(T))] + [b"$EndElementData\n"]
    path.write_bytes(b"".join(out))
    return path


def test_gmsh_element_data_meshio_refuses_is_read_past(tmp_path):
    # libigl's tutorial hand.msh (binary, as libigl's writeMSH writes it) raised "meshio could not
    # read it (Incompatible cell data ...)": meshlap reads no data, so the file is read once more
    # without its data sections; its tetrahedra give the .mesh file's spectrum
    meshio = pytest.importorskip("meshio")
    V, T = meshlap.samples.cube_tetrahedra(4)
    ref = meshlap.spectral.eigs(meshlap.laplacian(V, T, k=3), 5)[0]
    for binary in (0, 1):
        path = _gmsh22(tmp_path / f"cube{binary}.msh", V, T, binary)
        with pytest.raises(ValueError, match="Incompatible cell data"):
            meshio.read(path)
        P, cells, k = meshlap.inputs.read_input(path)
        assert k == 3 and np.array_equal(cells, T) and np.array_equal(P, V)
        assert np.array_equal(meshlap.io.read_tetrahedra(path)[1], T)
        np.testing.assert_allclose(meshlap.spectral.eigs(meshlap.laplacian(path), 5)[0], ref, rtol=1e-9,
                                   atol=1e-12)
    bad = tmp_path / "bad.msh"
    bad.write_bytes(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n$ElementData\nx\n$EndElementData\n")
    with pytest.raises(meshlap.MeshError, match="bad.msh: meshio could not read it"):
        meshlap.inputs.read_input(bad)


def test_info_build_and_curvature_of_clouds_and_volumes(capsys, cloud, tets, tmp_path):
    code, out, _ = run(capsys, "info", cloud)
    assert code == 0 and "point cloud (k=2" in out and "1,000" in out
    assert any(line.split()[:2] == ["parts", "1"] for line in out.splitlines())  # its stars join it
    area = float(next(line for line in out.splitlines() if line.startswith("surface area")).split()[-1])
    assert area == pytest.approx(4 * np.pi, rel=0.02)
    code, out, _ = run(capsys, "info", tets)
    volume = float(next(line for line in out.splitlines() if line.startswith("volume")).split()[-1])
    assert code == 0 and "1,296 tetrahedra" in out and volume == pytest.approx(1.0)
    fields = dict(re.split(r"\s{2,}", line, maxsplit=1) for line in out.splitlines() if line.strip())
    V, T = meshlap.samples.cube_tetrahedra(6)
    assert fields["why"].startswith("the input has tetrahedra: linear FEM on them")
    assert fields["nnz of S"].startswith(f"{meshlap.laplacian(V, T, k=3).assemble().nnz:,} ")
    code, _, _ = run(capsys, "build", tets, "-o", tmp_path / "cube.npz")
    op = meshlap.io.load_operator(tmp_path / "cube.npz")
    assert code == 0 and op.dim == 3 and op.geometry.source == "tetrahedra"
    code, out, _ = run(capsys, "curvature", cloud, "-o", tmp_path / "H.npy")
    H = np.load(tmp_path / "H.npy")
    assert code == 0 and "unsigned" in out and np.median(H) == pytest.approx(1.0, abs=0.03)
    fails(capsys, "curvature needs a surface or a point cloud", "curvature", tets)
    smoothed = tmp_path / "s.obj"
    fails(capsys, "smooth needs a surface mesh; this input is a volume", "smooth", tets, "-o", smoothed)
    fails(capsys, "smooth needs a surface mesh; this input is a point cloud", "smooth", cloud, "-o", smoothed)
    fails(capsys, "--compare-cot needs a surface mesh", "eigs", cloud, "-k", "3", "--compare-cot")


MALFORMED = {
    "noz.ply": (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                b"end_header\n0 0\n1 0\n0 1\n", "no vertex element with x, y, z"),
    "short.ply": (b"ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\n"
                  b"property float y\nproperty float z\nend_header\n\0\0\0\0",
                  "ends before its 100 vertices"),
    "words.xyz": (b"0 0 0\n1 zero 0\n", "not a number"),
    "empty.csv": (b"# nothing\n", "no rows of numbers"),
    "few.txt": (b"0 0 0\n1 0 0\n0 1 0\n", "needs at least 4 distinct points"),
    "junk.npy": (b"not an array", "not a NumPy .npy file"),
    "short.ele": ({"node": "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n", "ele": "1 4 0\n1 1 2 3 4\n"},
                  "announces 4 rows of 4 numbers; found 3"),
    "far.ele": ({"node": "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "ele": "1 4 0\n1 1 2 3 9\n"},
                "tetrahedron 1 refers to a node that does not exist"),
    "flat.ele": ({"node": "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 1 1 0\n", "ele": "1 4 0\n1 1 2 3 4\n"},
                 "zero measure"),
    "lonely.node": ({"node": "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"}, "no such TetGen file"),
    "bad.vtk": (b"garbage", "meshio could not read it (Illegal VTK header)"),
    "mni.obj": (b"P 0.3 0.3 0.4 10 1 3\n 0 0 0\n 1 0 0\n 0 1 0\n",
                "mni.obj: the file ends inside its normals (an MNI surface)"),
    "words.obj": (b"P 0.3 0.3 0.4 10 1 3\n 0 0 0\n 1 0 0\n 0 1 0\n0 0 1 0 0 1 0 0 1\n1 0 1 1 1 1\n3\n0 1 x\n",
                  "words.obj: a value of its index list is not a number"),
    **{f"empty.{suffix}": (b"", "the file is empty") for suffix in ("obj", "off", "ply", "stl", "xyz", "npy",
                                                                   "vtk", "vtu", "vtp", "glb", "npz")},
}


@pytest.mark.parametrize("name", MALFORMED)
def test_malformed_clouds_and_volumes_end_in_one_line(capsys, tmp_path, name):
    content, message = MALFORMED[name]
    path = tmp_path / name
    if isinstance(content, dict):
        for suffix, text in content.items():
            path.with_suffix("." + suffix).write_text(text)
    else:
        if name == "bad.vtk":
            pytest.importorskip("meshio")
        path.write_bytes(content)
    for command in ("info", "eigs"):
        fails(capsys, message, command, path)


def test_read_input_kinds(tmp_path, cloud, tets):
    P, cells, k = read_input(cloud)
    assert P.shape == (1000, 3) and cells is None and k is None
    V, T, k = read_input(tets)
    assert T.shape == (1296, 4) and k == 3
    (tmp_path / "c.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\n")
    assert read_input(tmp_path / "c.obj")[1].tolist() == [[0, 1], [1, 2]]


def test_eigs_of_lapys_tetrahedral_vtk(capsys, tets, tmp_path):
    """LaPy's TetMesh.write_vtk: legacy POLYDATA whose POLYGONS are tetrahedra (meshio refuses it);
    meshlap reads it as the same volume as the TetGen pair, and LaPy's TriaMesh file as a surface."""
    lapy = pytest.importorskip("lapy", reason="LaPy absent (pip install lapy)")
    V, T = meshlap.samples.cube_tetrahedra(6)
    lapy.TetMesh(V, T).write_vtk(str(tmp_path / "cubeTetra.vtk"))
    code, out, err = run(capsys, "eigs", tmp_path / "cubeTetra.vtk", "-k", "4")
    assert code == 0, err
    _, ref, _ = run(capsys, "eigs", tets, "-k", "4")
    np.testing.assert_allclose(eigenvalues(out), eigenvalues(ref), rtol=1e-5, atol=1e-12)
    Vr, Tr = meshlap.io.read_tetrahedra(tmp_path / "cubeTetra.vtk")
    assert np.array_equal(Tr, T) and np.abs(Vr - V).max() < 1e-6
    Vs, Fs = meshlap.shapes.sphere(300, seed=0)
    lapy.TriaMesh(Vs, Fs).write_vtk(str(tmp_path / "sphere.vtk"))
    P, cells, k = read_input(tmp_path / "sphere.vtk")
    assert k == 2 and np.array_equal(cells, Fs) and np.abs(P - Vs).max() < 1e-6


def test_legacy_vtk_quads_stay_a_surface_and_bad_ones_end_in_one_line(capsys, tmp_path):
    head = "# vtk DataFile Version 3.0\nquads\nASCII\nDATASET POLYDATA\n"
    grid = "POINTS 6 double\n0 0 0 1 0 0 2 0 0 0 1 0 1 1 0 2 1 0\n"
    (tmp_path / "quads.vtk").write_text(head + grid + "POLYGONS 2 10\n4 0 1 4 3\n4 1 2 5 4\nPOINT_DATA 6\n")
    V, cells, k = read_input(tmp_path / "quads.vtk")
    assert k == 2 and cells.tolist() == [[0, 1, 4, 3], [1, 2, 5, 4]] and V.shape == (6, 3)
    with pytest.raises(meshlap.MeshError, match="no tetrahedra in the file"):
        meshlap.io.read_tetrahedra(tmp_path / "quads.vtk")
    (tmp_path / "short.vtk").write_text(head + grid + "POLYGONS 2 10\n4 0 1 4 3\n4 1 2\n")
    fails(capsys, "malformed POLYGONS block", "info", tmp_path / "short.vtk")
    (tmp_path / "none.vtk").write_text(head + grid)
    fails(capsys, "a VTK POLYDATA file without POLYGONS or LINES", "info", tmp_path / "none.vtk")


def test_legacy_vtk_lines_are_a_curve_and_values_may_start_on_the_key_line(capsys, tmp_path):
    # vtk-data's bore.vtk (a well track) writes "LINES 1 45 44": the first value on the key's
    # line, which VTK reads as a stream of words; its faults.vtk and hello.vtk hold only lines,
    # which bound no surface: a curve
    head = "# vtk DataFile Version 2.0\ntrack\nASCII\nDATASET POLYDATA\n"
    n = 41
    s = np.linspace(0.0, 2.0, n)
    points = " ".join(f"{x:.17g} {0.5 * x:.17g} 0" for x in s)
    ids = " ".join(map(str, range(n)))
    (tmp_path / "track.vtk").write_text(head + f"POINTS {n} double {points}\nLINES 1 {n + 1} {n}\n{ids}\n")
    P, cells, k = read_input(tmp_path / "track.vtk")
    assert k == 1 and cells.tolist() == [[i, i + 1] for i in range(n - 1)] and np.allclose(P[:, 0], s)
    lam = meshlap.spectral.eigs(meshlap.laplacian(tmp_path / "track.vtk"), 3)[0]
    length = 2.0 * np.sqrt(1.25)  # Neumann on a segment: (jπ/ℓ)²
    assert np.allclose(lam, (np.pi * np.arange(3) / length) ** 2, rtol=1e-3, atol=1e-9)
    code, out, _ = run(capsys, "info", tmp_path / "track.vtk")
    assert code == 0 and "40 edges (curve)" in out


@pytest.mark.parametrize("version", [51, 42])
@pytest.mark.parametrize("binary", [True, False])
def test_pyvista_saved_polydata_is_read_as_written(capsys, tmp_path, binary, version):
    """pyvista's PolyData.save("x.vtk") writes legacy POLYDATA (binary, version 5.1: OFFSETS and
    CONNECTIVITY arrays), which meshio refuses; VTK writes 4.2 (a count before each cell) on
    request. Each is read as pyvista reads it, triangle strips as their triangles."""
    pv = pytest.importorskip("pyvista", reason="pyvista absent (pip install pyvista)")
    from vtkmodules.vtkIOLegacy import vtkPolyDataWriter

    sphere = pv.Sphere(theta_resolution=12, phi_resolution=9)
    for name, mesh in (("tris", sphere), ("strips", sphere.strip())):
        path = tmp_path / f"{name}.vtk"
        writer = vtkPolyDataWriter()
        writer.SetInputData(mesh)
        writer.SetFileName(str(path))
        writer.SetFileVersion(version)
        writer.SetFileType(2 if binary else 1)  # VTK_BINARY, VTK_ASCII
        writer.Write()
        V, F, k = read_input(path)
        tris = pv.read(path).triangulate()
        assert k == 2 and np.allclose(V, tris.points) and len(F) == tris.n_cells == sphere.n_cells
        assert sorted(map(sorted, F.tolist())) == sorted(map(sorted, tris.regular_faces.tolist()))
        normals = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        assert np.all(np.einsum("ij,ij->i", normals, V[F].mean(axis=1)) > 0)  # outward, as written
    code, out, _ = run(capsys, "smooth", path, "-o", tmp_path / "smooth.obj")  # every command reads it
    assert code == 0 and (tmp_path / "smooth.obj").exists()
    data = path.read_bytes()
    path.write_bytes(data[:len(data) // 2])
    cut = r"^strips\.vtk: (the file ends inside its|malformed) \w+ block"  # said once, not wrapped
    with pytest.raises(meshlap.MeshError, match=cut):
        read_input(path)


def test_formats_meshio_does_not_read_go_to_pyvista_and_trimesh(capsys, tmp_path):
    """VTK's XML polydata (.vtp, pyvista's own format) through pyvista and a glTF scene (.glb)
    through trimesh, each read as its package reads it; a bad file ends in one line naming the
    reader."""
    pv = pytest.importorskip("pyvista", reason="pyvista absent (pip install pyvista)")
    trimesh = pytest.importorskip("trimesh", reason="trimesh absent (pip install trimesh)")
    sphere = pv.Sphere(theta_resolution=12, phi_resolution=9)
    sphere.save(tmp_path / "s.vtp")
    V, F, k = read_input(tmp_path / "s.vtp")
    assert k == 2 and np.allclose(V, sphere.points) and np.array_equal(F.triangles(), sphere.regular_faces)
    P = np.random.default_rng(0).random((50, 3))
    pv.PolyData(P).save(tmp_path / "c.vtp")
    Q, cells, _ = read_input(tmp_path / "c.vtp")
    assert cells is None and np.allclose(Q, P)
    ico = trimesh.creation.icosphere(subdivisions=2)
    ico.export(tmp_path / "s.glb")
    V, F, k = read_input(tmp_path / "s.glb")
    assert k == 2 and np.allclose(V, ico.vertices) and np.array_equal(F, ico.faces)
    code, out, _ = run(capsys, "info", tmp_path / "s.glb")
    assert code == 0 and "320 triangles" in out
    (tmp_path / "bad.vtp").write_text("garbage")
    fails(capsys, "bad.vtp: pyvista read no points from it", "info", tmp_path / "bad.vtp")
    (tmp_path / "bad.glb").write_text("garbage")
    fails(capsys, "bad.glb: trimesh could not read it", "info", tmp_path / "bad.glb")
