"""Every tuned constant of meshlap's builders, in one place, each with where it came from.

A constant here was chosen from measurements (a benchmark's rows, a sweep of the value), not
derived: change it here, re-run what its comment names and record the new rows in
``benchmarks/RESULTS.md`` (the issue numbers name its sections). Mathematical constants
(quadrature rules, the Gaussian's cut-off) and plain limits (chunk and sample sizes, memory)
stay in the modules that use them. ``tests/test_structure.py`` checks that each name here is
used by meshlap and has its line of provenance.
"""

from __future__ import annotations

__all__ = ["CLOUD_CAP_FLOOR", "CLOUD_NOISY", "CORRECTED_TOL", "CREASE_ANGLE", "CREASE_WIDTHS",
           "CURVATURE_LIMIT", "DENOISE_DT", "DENOISE_H", "DENOISE_STEPS", "FEATURE_FLOOR",
           "FEATURE_THIN_WIDTHS", "FEM_TIE", "GALERKIN_H_SCALE", "H_SCALE", "NOISE_AREA", "NOISE_FLOOR",
           "NOISE_QUANTILE", "NOISE_ROUGHNESS", "NOISE_SPREAD", "NOISE_STEP", "NOISE_UNEXPLAINED", "PSD_RTOL",
           "QUADRATIC_MAX_UNKNOWNS",
           "PSD_STOP_TOL", "ROW_BETA", "ROW_C_COMPACT", "ROW_C_WIDE", "ROW_EXCESS", "ROW_FLOORS",
           "ROW_GAMMA", "ROW_K_NOISE", "ROW_K_PER_MONOMIAL", "ROW_LADDER", "ROW_MARGIN", "ROW_NOISY",
           "ROW_ROBUST", "ROW_ROUNDING", "ROW_SAMPLE", "SEGMENT_STEP", "SHEET_DETOUR", "SHORTCUT_RATIO",
           "SPLIT_BELOW", "STAR_NEIGHBORS", "STAR_SCATTER", "STAR_THIN"]

# -- the kernel's width, truncation and check (meshlap.widths, .options, .corrections.psd) -----
#: c of h = c·ē² by dimension (tetrahedra: face diagonals are edges); docs/accuracy.md's width sweeps
H_SCALE = {1: 8.0, 2: 4.0, 3: 4.0, "tetrahedra": 0.5}
#: β of the cap h_w = min(h, β/κ_w²); docs/accuracy.md: spot 7.7% → 1.1%, fandisk 5.0% → 3.2%
CURVATURE_LIMIT = 0.05
#: A cloud's cap stops at this fraction of h: 1,000-point random torus 33% → 5.0% (bench_cloud_cap.py)
CLOUD_CAP_FLOOR = 0.5
#: Kernel tolerance of the corrected kernel: 16k sphere, 24.5% fewer entries than 1e-8, Δλ 1.9e-6 (i19)
CORRECTED_TOL = 1e-6
#: −S is semidefinite when λ_min ≥ −PSD_RTOL·max(−L_ww): bench_psd.py, 35 inputs against LAPACK (i19p)
PSD_RTOL = 1e-6
#: The check's LOBPCG stopping fraction: 3e-2 and 0.1 each missed a failure of bench_psd.py's sweep (i19)
PSD_STOP_TOL = 1e-3

# -- the Galerkin pencil (meshlap.corrections.galerkin, .shortcuts, .features) -------------------
#: Its h = c·ē²: at 0.25 three points per triangle lose 1% on the 4,000-vertex square (bench_quadrature)
GALERKIN_H_SCALE = 0.5
#: Normals differing by more than this (degrees) mark a crease: the cube's 90° ones, 5.8% → 0.04%; not swept
CREASE_ANGLE = 60.0
#: Curve segments cut into pieces of ≤ this·√h: the 2,000-random-angle circle 0.00289% at 0.5 and at 0.25
SEGMENT_STEP = 0.5
#: Triangles narrower than this·h at a corner are cut: at 1, spot 0.96% → 0.92%, fandisk unchanged (i19)
SPLIT_BELOW = 0.64
#: Pairs whose path exceeds this times their chord are dropped: fandisk 1.33% → 0.14%, spot 1.32% (i19)
SHORTCUT_RATIO = 1.25
#: The width narrows within this many widths √(2h) of a groove: fandisk 0.087% at 2, 0.26% at 1-1.5 (i19)
CREASE_WIDTHS = 2.0
#: ... or where half its thickness is under this many: spot 0.91-0.94%; at 2 the torus 0.95% → 1.49% (i19)
FEATURE_THIN_WIDTHS = 1.5
#: ... to no less than this fraction of h, triangles cut in 4: fandisk and spot of bench_spectra.py (i19)
FEATURE_FLOOR = 0.5
#: Face-normal roughness above which nothing narrows: ~1 smooth, 3.65 at 0.5% radial noise (test_galerkin)
NOISE_ROUGHNESS = 3.0

# -- the fitted point-wise rows (meshlap.corrections.rowchoice; issue 20, bench_pointwise.py) ----
#: Weight of the probes (bias) in the predicted error, measured on spheres (rowchoice's module notes)
ROW_BETA = 0.1
#: Weight of the noise factor in it: within about 2× of x², eˣ's error, 2,000-16,000 points, 0-1% noise
ROW_GAMMA = 0.6
#: A compact row's K-th neighbour weighs e^-c: clean spot E2 0.080 → 0.035 against e^-8 (bench_pointwise)
ROW_C_COMPACT = 12.0
#: A wide row's K-th neighbour weighs e^-c: issue 20's noisy rows (bench_pointwise.py); not swept since
ROW_C_WIDE = 3.0
#: Neighbours of a compact row per monomial of its degree (plus 4): issue 20 (bench_pointwise.py)
ROW_K_PER_MONOMIAL = 1.7
#: Neighbours of the noise and curvature fits: issue 20 (bench_pointwise.py)
ROW_K_NOISE = 64
#: Noise over spacing above which the scale is the wider curvature fit's: issue 20 (bench_pointwise.py)
ROW_NOISY = 1e-3
#: The wide stencils' K grows by this factor up to max_neighbors: issue 20 (bench_pointwise.py)
ROW_LADDER = 4.0
#: Most points a wide row holds: 96 of 1,000 lose 10-40% of the accuracy at a sixth of the cost (16k noisy)
ROW_SAMPLE = 96
#: Candidates within this of the least predicted error may win by lower bias: Table 4 E2 0.025 → 0.0097
ROW_ROBUST = 2.0
#: Noise under this many rounding units is arithmetic's: clean 10⁶-point sphere's ladder cost 25 s for nothing
ROW_ROUNDING = 16.0
#: A residual beyond this multiple of the noise level is missed shape: spot's clean E2 0.080 → 0.035 with it
ROW_EXCESS = 2.0
#: The sample's least noise factor and probes times these bound the rest: all of 16,000 sphere points
ROW_FLOORS = (0.5, 0.25, 0.25)
#: Degree > 2 predicted this much more accurate marks a point clean: E2 unchanged on bench_pointwise
ROW_MARGIN = 10.0

# -- a cloud's local Delaunay stars (meshlap.geometry.pointcloud, .stars; cloud_neighbors.py) -----
#: Their first neighbourhood by dimension (doubled where a star stays open): surfaces' 16 the best of
#: 8-45 on bench_real.py's 50 clouds (49 within 1.5× of robust-laplacian, median 0.82×); 1 and 3 not swept
STAR_NEIGHBORS = {1: 8, 2: 16, 3: 32}
#: Width of a first neighbourhood (median distance across its plane's first axis over along it)
#: below which it lies along a line (a scan line's), which fixes no tangent plane: a surface's
#: measured 0.14 or more (a random sphere's, a disc's rim, a two-row ribbon), a line's is about its
#: bending κρ/4 (0.028 on a helix sampled 100 points per radian)
STAR_THIN = 0.1
#: Detour over the agreed star edges beyond which an edge joins two sheets: a flipped quad's
#: diagonal is joined by two sides (at most about 2x its length on a sampling whose triangles keep
#: angles above 30°); the corpus's touching vertices (benchmarks/real_corpus.touching) use 4 too
SHEET_DETOUR = 4.0
#: Median heights above which a steep first neighbour is on another sheet: 49 of 50 for any of 1.5-6
STAR_SCATTER = 3.0

# -- noise (meshlap.geometry.pointcloud, meshlap.denoise) and welding (meshlap.fem) --------------
#: A cloud's σ̂²/a² above which it is projected by default: clean < 1e-3, 1% noise 0.025-0.095 (pointclouds.md)
CLOUD_NOISY = 0.02
#: Share of it cubic fits leave, within this of 1 for noise (χ²-normed): missed shape 0.33-0.87, rounding 1.4
NOISE_UNEXPLAINED = 0.9
#: Their quartile ratio over χ²'s, within this of 1 for noise: noisy scans 0.96-1.13, a clean knight 1.45
NOISE_SPREAD = 1.25
#: c of the denoising step τ = (cσ̂)² (bi-Laplacian): five noisy real meshes at 0.3ē 1.9-11% (c = 1:
#: 12-16%, c = 3: 3.6-32%; COT 16-19%), at 0.1ē 1.5-2.6% (c = 3: 1.3-6.8%; COT 2.6-4.1%), denoise=True
#: (bench_real.py --only spot,cow,bunny-igl,fertility,homer --no-write --noise-step c)
NOISE_STEP = 2.0
#: Area normal noise σ adds, in (σ/ē)² of a part's: 1.17-1.22 at 0.3ē on spot, cow, bunny, fertility, homer
NOISE_AREA = 2.2
#: Area noise adds (NOISE_AREA·σ̂²/a²) below which a surface is left: under every corpus mesh's own error
NOISE_FLOOR = 1e-4
#: Unknowns of the quadratic elements (vertices + edges + triangles, about 6 per vertex) up to which
#: eigs solves them by default: their factorization grows faster than N; random 16,000-vertex
#: sphere (96,000): 6.4 s of CPU for build + 10 pairs, 32,000 vertices 14.5 s (linear 1.8 s)
QUADRATIC_MAX_UNKNOWNS = 100_000
#: Quantile of the vertices' noise read: spot, fandisk lower quartile 0.014 and 0 clean, 0.27-0.29ē at 0.3ē
NOISE_QUANTILE = 0.25
#: Seam copies tied at this times their vertex's diagonal: their modes (~4× its own) above the smooth ones
FEM_TIE = 1.0

# -- the denoising flow (meshlap.smoothing; benchmarks/bench_smoothing.py) -----------------------
#: Its step in units of σ̂²: fandisk, spot at 0.15-0.5ē of noise within 1% of the best dt, spot at 0.15ē 7%
DENOISE_DT = 4.0
#: Its steps: two of 4σ̂² diffuse over √(2·8σ̂²) = 4σ̂ (bench_smoothing.py)
DENOISE_STEPS = 2
#: Its pencil's width in ē²: the spectra's ē²/2 leaves the highest frequencies' noise (bench_smoothing.py)
DENOISE_H = 0.25
