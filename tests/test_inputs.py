"""Objects users already hold (trimesh, pyvista, open3d, meshio) go straight into the builders."""

import numpy as np
import pytest

import meshlap
from meshlap.inputs import as_geometry_input, boundary_triangles

V, F = meshlap.shapes.sphere(400, seed=0)
VT, T = meshlap.samples.cube_tetrahedra(3)
P = meshlap.samples.sphere_points(500)


def same_operator(a, b, f):
    return np.array_equal(a @ f, b @ f) and np.array_equal(a.mass, b.mass)


def test_trimesh_objects():
    trimesh = pytest.importorskip("trimesh")
    mesh = trimesh.Trimesh(V, F, process=False)
    assert same_operator(meshlap.laplacian(mesh, h=0.02), meshlap.laplacian(V, F, h=0.02), V)
    cloud = trimesh.PointCloud(P)
    assert same_operator(meshlap.point_cloud_laplacian(cloud, h=0.03),
                         meshlap.point_cloud_laplacian(P, h=0.03), P)


def test_pyvista_objects():
    pv = pytest.importorskip("pyvista")
    faces = np.column_stack([np.full(len(F), 3), F]).ravel()
    surf = pv.PolyData(V, faces)
    assert same_operator(meshlap.laplacian(surf, h=0.02), meshlap.laplacian(V, F, h=0.02), V)
    quads = pv.Plane(i_resolution=6, j_resolution=5)  # quads stay quads
    Vq, Fq, k = as_geometry_input(quads)
    assert k == 2 and Fq.sizes.tolist() == [4] * 30
    cells = np.column_stack([np.full(len(T), 4), T]).ravel()
    grid = pv.UnstructuredGrid(cells, np.full(len(T), pv.CellType.TETRA, dtype=np.uint8), VT)
    vol = meshlap.laplacian(grid)
    assert vol.dim == 3 and vol.mass.sum() == pytest.approx(1.0)
    assert same_operator(vol, meshlap.laplacian(VT, T, k=3), VT)
    assert same_operator(meshlap.point_cloud_laplacian(pv.PolyData(P), h=0.03),
                         meshlap.point_cloud_laplacian(P, h=0.03), P)
    # the hull of the tetrahedra is a closed surface: Euler characteristic 2
    hull = boundary_triangles(T)
    edges = {tuple(sorted(e)) for t in hull.tolist() for e in ((t[0], t[1]), (t[1], t[2]), (t[0], t[2]))}
    assert len(np.unique(hull)) - len(edges) + len(hull) == 2


def test_scenes_are_their_parts():
    """A pyvista MultiBlock and a trimesh Scene of two spheres: one operator on both parts, two
    zero eigenvalues (one per part), the Scene's meshes where its transforms place them."""
    pv, trimesh = pytest.importorskip("pyvista"), pytest.importorskip("trimesh")
    faces = np.column_stack([np.full(len(F), 3), F]).ravel()
    blocks = pv.MultiBlock([pv.PolyData(V, faces), pv.PolyData(V + [3.0, 0, 0], faces)])
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.Trimesh(V, F, process=False))
    scene.add_geometry(trimesh.Trimesh(V, F, process=False),
                       transform=trimesh.transformations.translation_matrix([3.0, 0, 0]))
    alone = meshlap.spectral.eigs(meshlap.laplacian(V, F), 2)[0][1]  # 2.0156: each part as if alone
    for obj, n_parts in ((blocks, 2), (scene, 2)):
        P_, cells, _ = as_geometry_input(obj)
        assert len(P_) == n_parts * len(V) and np.ptp(P_[:, 0]) == pytest.approx(5.0, abs=0.02)
        lam = meshlap.spectral.eigs(meshlap.laplacian(obj), n_parts + 1)[0]
        assert np.abs(lam[:n_parts]).max() < 1e-10 and lam[n_parts] == pytest.approx(alone, rel=1e-9)


def test_grids_of_hexahedra_are_split_or_refused_never_read_as_points():
    """A pyvista grid of voxels or hexahedra (ImageData, StructuredGrid, a .vti/.vts file) is split
    into tetrahedra by VTK, conformingly: the unit cube's first Neumann eigenvalue π² three times
    after one zero. Cells meshlap does not take, in an object it cannot split (meshio), raise an
    error naming them: they had been dropped, leaving a surface point cloud of the corners."""
    pv, meshio = pytest.importorskip("pyvista"), pytest.importorskip("meshio")
    cube = pv.ImageData(dimensions=(9, 9, 9), spacing=(1 / 8,) * 3)
    for grid in (cube, cube.cast_to_structured_grid()):
        P_, cells, k = as_geometry_input(grid)
        assert k == 3 and cells.shape[1] == 4 and len(P_) == 729
        lam = meshlap.spectral.eigs(meshlap.laplacian(grid), 5)[0]
        assert abs(lam[0]) < 1e-10 and np.abs(lam[1:4] / np.pi**2 - 1).max() < 0.04
        assert lam[4] > 1.8 * np.pi**2
    hexes = cube.cast_to_structured_grid().cast_to_unstructured_grid().cells_dict[12]
    for blocks in ([("hexahedron", hexes)], [("hexahedron", hexes), ("triangle", np.array([[0, 1, 9]]))]):
        with pytest.raises(meshlap.MeshError, match="holds 512 hexahedron cells, which meshlap does not"):
            as_geometry_input(meshio.Mesh(cube.points, blocks))

    class Cells:  # a cell kind named nowhere (a polyhedron) is refused too; vertex cells add nothing
        points = VT
        cells_dict = {"polyhedron": T, "vertex": np.arange(len(VT))[:, None]}

    with pytest.raises(meshlap.MeshError, match=f"holds {len(T)} polyhedron cells"):
        as_geometry_input(Cells())
    Cells.cells_dict = {"tetra": T, "vertex": np.arange(len(VT))[:, None]}
    assert as_geometry_input(Cells())[2] == 3


def test_vtk_files_of_hexahedra_are_read_by_pyvista_and_split(tmp_path):
    """A .vtu or .vtk file of hexahedra, which meshio reads but meshlap does not take, goes to
    pyvista's reader and VTK splits it into tetrahedra, as a pyvista grid is (it had raised
    "holds 512 hexahedron cells"): the unit cube's π² three times after one zero."""
    pv, meshio = pytest.importorskip("pyvista"), pytest.importorskip("meshio")
    cube = pv.ImageData(dimensions=(9, 9, 9), spacing=(1 / 8,) * 3).cast_to_structured_grid()
    cube = cube.cast_to_unstructured_grid()
    for suffix in (".vtu", ".vtk"):
        path = tmp_path / f"hexes{suffix}"
        meshio.write(path, meshio.Mesh(np.asarray(cube.points), [("hexahedron", cube.cells_dict[12])]))
        P_, cells, k = meshlap.inputs.read_input(path)
        assert k == 3 and cells.shape == (512 * 6, 4) and len(P_) == 729
        lam = meshlap.spectral.eigs(meshlap.laplacian(P_, cells, k=3), 4)[0]
        assert abs(lam[0]) < 1e-10 and np.abs(lam[1:4] / np.pi**2 - 1).max() < 0.04


def test_meshio_objects(tmp_path):
    meshio = pytest.importorskip("meshio")
    vol = meshio.Mesh(VT, [("triangle", boundary_triangles(T)), ("tetra", T)])
    assert same_operator(meshlap.laplacian(vol), meshlap.laplacian(VT, T, k=3), VT)
    surf = meshio.Mesh(V, [("triangle", F)])
    assert same_operator(meshlap.laplacian(surf, h=0.02), meshlap.laplacian(V, F, h=0.02), V)
    path = tmp_path / "cube.vtu"
    meshio.write(path, vol)
    assert same_operator(meshlap.laplacian(str(path)), meshlap.laplacian(VT, T, k=3), VT)


def test_open3d_like_objects():
    # open3d's geometry classes, by the attributes meshlap reads (open3d itself is large;
    # when it is installed, its own classes are checked below)
    class TriangleMesh:
        vertices, triangles = V, F

    class TetraMesh:
        vertices, tetras = VT, T

    class PointCloud:
        points = P

    assert same_operator(meshlap.laplacian(TriangleMesh(), h=0.02), meshlap.laplacian(V, F, h=0.02), V)
    assert meshlap.laplacian(TetraMesh()).dim == 3
    assert same_operator(meshlap.point_cloud_laplacian(PointCloud(), h=0.03),
                         meshlap.point_cloud_laplacian(P, h=0.03), P)
    o3d = pytest.importorskip("open3d")
    mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(V), o3d.utility.Vector3iVector(F))
    assert same_operator(meshlap.laplacian(mesh, h=0.02), meshlap.laplacian(V, F, h=0.02), V)
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(P))
    assert same_operator(meshlap.point_cloud_laplacian(cloud, h=0.03),
                         meshlap.point_cloud_laplacian(P, h=0.03), P)
    tets = o3d.geometry.TetraMesh(o3d.utility.Vector3dVector(VT), o3d.utility.Vector4iVector(T))
    assert same_operator(meshlap.laplacian(tets), meshlap.laplacian(VT, T, k=3), VT)


def test_unknown_objects_are_refused():
    with pytest.raises(meshlap.MeshError, match="cannot read a mesh or point cloud from a dict"):
        meshlap.laplacian({"V": V})


def test_points_alone_in_an_object_or_a_file_are_a_cloud(tmp_path):
    # laplacian(x) of an object or file holding points alone is point_cloud_laplacian(x), as the
    # command line reads such a file (it had raised "F must be ... got None")
    cloud = type("Cloud", (), {"points": P})()
    assert same_operator(meshlap.laplacian(cloud, h=0.03), meshlap.point_cloud_laplacian(P, h=0.03), P)
    np.savetxt(tmp_path / "cloud.xyz", P)
    assert same_operator(meshlap.laplacian(tmp_path / "cloud.xyz", h=0.03),
                         meshlap.point_cloud_laplacian(P, h=0.03), P)
    reason = meshlap.laplacian(tmp_path / "cloud.xyz").decision.reason
    assert reason.startswith("a surface's or a curve's point cloud")
