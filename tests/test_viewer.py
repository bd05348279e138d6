"""The interactive viewer: k3d plots, standalone HTML, and that HTML rendered in a real browser.

The browser check runs Chromium headless with software WebGL (SwiftShader) and no network;
CI installs Debian's chromium (.ci/run). Where it could not be installed, .ci/run says why in
MESHLAP_NO_CHROMIUM and the test is skipped with that reason.
"""

import functools
import http.server
import os
import re
import shutil
import subprocess
import threading
import time

import numpy as np
import pytest

import meshlap
from meshlap import plot

k3d = pytest.importorskip("k3d", reason='the viewer needs k3d (pip install "meshlap[view]")')
from test_cli import run  # noqa: E402

V, F = meshlap.shapes.sphere(2000, seed=0)
BROWSERS = ("chromium", "chromium-browser", "google-chrome")


def chromium():
    found = next((shutil.which(b) for b in BROWSERS if shutil.which(b)), None)
    if found is None:
        reason = "Chromium is not installed (CI installs it: .ci/run)"
        pytest.skip(os.environ.get("MESHLAP_NO_CHROMIUM", reason))
    return found


class _Pages(http.server.SimpleHTTPRequestHandler):
    """Serves the test's folder; /wait answers after a few seconds, which holds the page's load
    event (and so the screenshot) until k3d has drawn. Every requested path is recorded."""

    requested: list = []

    def do_GET(self):
        self.requested.append(self.path)
        if self.path.startswith("/wait"):
            time.sleep(6)
            self.send_response(204)
            self.end_headers()
            return
        super().do_GET()

    def log_message(self, *args):
        pass


def screenshot(html, png, size=(900, 600)):
    """Render the page in headless Chromium with software WebGL and no name resolution
    (nothing but 127.0.0.1 can be reached); returns the RGB image and the paths requested."""
    import matplotlib.image

    page = html.with_name("view-" + html.name)
    page.write_text(html.read_text().replace("</body>", '<img src="/wait" alt=""></body>'))
    handler = functools.partial(_Pages, directory=str(html.parent))
    _Pages.requested = []
    with http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler) as server:
        threading.Thread(target=server.serve_forever, daemon=True).start()
        subprocess.run([chromium(), "--headless", "--no-sandbox", "--enable-unsafe-swiftshader",
                        "--use-angle=swiftshader", "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",
                        f"--window-size={size[0]},{size[1]}", f"--screenshot={png}",
                        f"http://127.0.0.1:{server.server_address[1]}/{page.name}"],
                       capture_output=True, timeout=120, check=False)
        server.shutdown()
    return matplotlib.image.imread(png)[..., :3], list(_Pages.requested)


def test_show_builds_meshes_points_and_labels():
    p = plot.show(V, F, V[:, :2], titles=["x", "y"])
    meshes = [o for o in p.objects if o.type == "Mesh"]
    assert len(meshes) == 2 and [o.text for o in p.objects if o.type == "Text"] == ["x", "y"]
    assert meshes[0].color_range == pytest.approx([V[:, 0].min(), V[:, 0].max()], rel=1e-6)
    # the second copy sits beside the first, one bounding box and a gap away
    shift = meshes[1].vertices[:, 0].min() - meshes[0].vertices[:, 0].min()
    assert shift == pytest.approx(2 * 1.3, rel=1e-3)
    cloud = plot.show(meshlap.samples.sphere_points(500), None, symmetric=True)
    assert [o.type for o in cloud.objects] == ["Points"]
    op = meshlap.laplacian(V, F)
    modes = plot.show_modes(op, 3)
    lam = meshlap.spectral.eigs(op, 4)[0]
    labels = [o.text for o in modes.objects if o.type == "Text"]
    assert labels == [f"φ{i}  λ = {lam[i]:.4g}" for i in (1, 2, 3)]
    with pytest.raises(meshlap.MeshError, match="unknown colormap"):
        plot.show(V, F, V[:, 0], cmap="no-such-map")
    with pytest.raises(meshlap.MeshError, match="writes .html files"):
        plot.save_html(p, "view.png")


def test_exported_html_is_standalone(tmp_path):
    path = plot.save_html(plot.show(V, F, V[:, 2]), tmp_path / "sphere.html")
    html = path.read_text()
    assert "<script" in html and len(html) > 500_000  # k3d's JavaScript travels in the file
    # no script, style or image is fetched: every src/href is local (the browser test below
    # renders the page with every host name unresolvable)
    assert not re.findall(r"""(?:src|href)\s*=\s*["']?(?:https?:)?//""", html)


def test_browser_renders_the_mesh_in_its_colours(tmp_path):
    path = plot.save_html(plot.show(V, F, V[:, 2], cmap="viridis"), tmp_path / "sphere.html")
    image, requested = screenshot(path, tmp_path / "sphere.png")
    # nothing but the page itself (and the browser's own favicon request)
    assert set(requested) - {"/favicon.ico"} == {"/view-sphere.html", "/wait"}
    assert image.std() > 0.05, "blank screenshot"
    # the mesh: pixels away from the white background, right of the colour legend (bottom left)
    body = image[:, 150:].reshape(-1, 3)
    body = body[np.abs(body - 1.0).max(axis=1) > 0.1]
    assert len(body) > 0.05 * image[:, 150:, 0].size
    cmap = np.array(k3d.colormaps.matplotlib_color_maps.Viridis).reshape(-1, 4)
    ramp = np.stack([np.interp(np.linspace(0, 1, 256), cmap[:, 0], cmap[:, c]) for c in (1, 2, 3)], axis=1)
    # lighting scales a colour: compare hues, the directions of the RGB vectors
    unit = body / np.linalg.norm(body, axis=1, keepdims=True).clip(1e-6)
    hues = ramp / np.linalg.norm(ramp, axis=1, keepdims=True)
    dist = np.linalg.norm(unit[:, None, :] - hues[None], axis=2)
    near = dist.min(axis=1) < 0.05
    where = dist.argmin(axis=1)[near] / 255
    assert near.mean() > 0.8, near.mean()  # the colormap's colours, lit and shaded
    assert where.min() < 0.2 and where.max() > 0.8  # both ends of z: the whole ramp is on screen


def test_cli_html_of_eigenfunctions_renders(capsys, tmp_path):
    meshlap.io.write_mesh(tmp_path / "sphere.obj", V, F)
    code, out, _ = run(capsys, "eigs", tmp_path / "sphere.obj", "-k", "5", "--html", tmp_path / "modes.html")
    assert code == 0 and "wrote" in out
    image, _ = screenshot(tmp_path / "modes.html", tmp_path / "modes.png")
    assert image.std() > 0.05
    code, out, _ = run(capsys, "curvature", tmp_path / "sphere.obj", "--html", tmp_path / "H.html")
    assert code == 0 and (tmp_path / "H.html").stat().st_size > 500_000
    assert f"wrote {tmp_path / 'H.html'}" in out
    # red and blue of RdBu_r: signed eigenfunctions on four copies
    red = (image[..., 0] > 0.6) & (image[..., 2] < 0.35)
    blue = (image[..., 2] > 0.6) & (image[..., 0] < 0.35)
    assert red.sum() > 500 and blue.sum() > 500
