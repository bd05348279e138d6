"""The compiled kernels of :mod:`meshlap.corrections.highorder`: a frame per centre and the
weighted least-squares rows, of one or several degrees on the same stencil."""

import math

import numpy as np

from .._dense import chol_solve, cholesky, sym_eigh
from .._jit import jit

# A Cholesky pivot below this fraction of its diagonal means the monomial adds nothing new.
PIVOT_TOL = 1e-11
# Every divisor in the fit is nonzero by construction (a weight sum holding the centre's 1, a
# pivot above its floor, a guarded radius): IEEE division without numba's ZeroDivisionError test,
# the same numbers for 3-10% less CPU a fit (16,000 points, degrees 2-6, with meshlap._dense's)
_IEEE = "numpy"


@jit(error_model=_IEEE)
def _covariance3(P, nbr, th, tot, mean, C):  # pragma: no cover - compiled
    # _frame's weighted mean and covariance in three dimensions: the same sums in the same order
    # (the same numbers), side by side in registers, where the general loops keep one running
    # sum at a time or keep them in memory
    s0 = s1 = s2 = 0.0
    for j in range(len(nbr)):
        p = nbr[j]
        s0 += th[j] * P[p, 0]
        s1 += th[j] * P[p, 1]
        s2 += th[j] * P[p, 2]
    m0, m1, m2 = s0 / tot, s1 / tot, s2 / tot
    mean[0], mean[1], mean[2] = m0, m1, m2
    c00 = c10 = c11 = c20 = c21 = c22 = 0.0
    for j in range(len(nbr)):
        p = nbr[j]
        x0, x1, x2 = P[p, 0] - m0, P[p, 1] - m1, P[p, 2] - m2
        t = th[j]
        c00 += t * x0 * x0
        c10 += t * x1 * x0
        c11 += t * x1 * x1
        c20 += t * x2 * x0
        c21 += t * x2 * x1
        c22 += t * x2 * x2
    C[0, 0], C[1, 0], C[1, 1], C[2, 0], C[2, 1], C[2, 2] = c00, c10, c11, c20, c21, c22


@jit(error_model=_IEEE)
def _frame(P, w, nbr, th, normal, use_normal, B, C, ev, vec, v):  # pragma: no cover - compiled
    # B: orthonormal rows, the first k tangent, the rest normal; C, vec (d × d), ev, v (d) scratch
    d = P.shape[1]
    if use_normal:
        # a hypersurface: the given normal, tangents by Gram–Schmidt of the coordinate axes
        for a in range(d):
            B[d - 1, a] = normal[a]
        row = 0
        for e in range(d):
            if row == d - 1:
                break
            for a in range(d):
                v[a] = 1.0 if a == e else 0.0
            for r in range(row):
                dot = 0.0
                for a in range(d):
                    dot += v[a] * B[r, a]
                for a in range(d):
                    v[a] -= dot * B[r, a]
            dot = 0.0
            for a in range(d):
                dot += v[a] * normal[a]
            for a in range(d):
                v[a] -= dot * normal[a]
            nv = 0.0
            for a in range(d):
                nv += v[a] * v[a]
            nv = math.sqrt(nv)
            if nv > 0.3:
                for a in range(d):
                    B[row, a] = v[a] / nv
                row += 1
        return
    tot = 0.0
    for j in range(len(nbr)):
        tot += th[j]
    mean = v
    if d == 3:
        _covariance3(P, nbr, th, tot, mean, C)
    else:
        for a in range(d):
            s = 0.0
            for j in range(len(nbr)):
                s += th[j] * P[nbr[j], a]
            mean[a] = s / tot
        for a in range(d):
            for b in range(d):
                C[a, b] = 0.0
        for j in range(len(nbr)):
            for a in range(d):
                xa = P[nbr[j], a] - mean[a]
                for b in range(a + 1):
                    C[a, b] += th[j] * xa * (P[nbr[j], b] - mean[b])
    for a in range(d):
        for b in range(a):
            C[b, a] = C[a, b]
    sym_eigh(C, ev, vec)
    for r in range(d):
        for a in range(d):
            B[r, a] = vec[a, d - 1 - r]


@jit(fastmath=True)
def _dots(A, x, n, K, out):  # pragma: no cover - compiled
    # out[a] = Σ_j A[a, j] x[j] for the first n rows: sums over contiguous rows, which the
    # compiler vectorizes
    for a in range(n):
        s = 0.0
        for j in range(K):
            s += A[a, j] * x[j]
        out[a] = s


@jit(error_model=_IEEE)
def _rows(start, stop, order, P, centers, indptr, starts, indices, hv, normals, use_normals, k, parent,
          var, count, pair, targets, idx1, idx2, want_noise, keep, out, used, resid, amp, bias,
          kap):  # pragma: no cover - compiled
    # one stencil, frame and Gram matrix serve the rows of every degree in targets (the
    # Cholesky factor of a leading block is the leading block of the factor); outputs by
    # target. The Gram matrix G_ab = Σ_j θ_j Φ_a Φ_b is read from the moments Σ_j θ_j Φ_e of
    # the monomials of degree ≤ 2q (pair[a, b]: the monomial Φ_a Φ_b): at degree 6 on a
    # surface 91 sums over the neighbours instead of 406
    d = P.shape[1]
    nc = d - k
    # the frame's and the metric's scratch, once per block
    B = np.empty((d, d))
    C = np.empty((d, d))
    vec = np.empty((d, d))
    ev = np.empty(d)
    v = np.empty(d)
    Gi = np.empty((k, k))
    Lk = np.empty((k, k))
    kfloor = np.zeros(k)
    kcol = np.empty(k)
    # the rows' scratch, once per block for its longest row (np.empty and np.zeros of one and
    # two dimensions only: each other allocation, np.ones or a third dimension, is one more
    # numba overload to compile)
    Kb = 0
    for i in range(start, stop):
        r = order[i]
        Kb = max(Kb, indptr[r + 1] - indptr[r])
    # Vandermonde up to twice the degree (the moments; it holds the two more degrees of the
    # probes of the error model), stored by monomial (rows contiguous over the neighbours)
    degree = 0
    for ti in range(len(targets)):
        degree = max(degree, targets[ti])
    top = min(degree + 2, len(count) - 1)
    m = count[degree]
    nmom = count[min(2 * degree, len(count) - 1)]
    mb = max(count[top], nmom)
    X = np.empty((Kb, d))
    th = np.empty(Kb)
    U = np.empty((k, Kb))  # by coordinate: contiguous over the neighbours
    Z = np.empty((nc, Kb))
    Phi = np.empty((mb, Kb))
    mom = np.empty(mb)
    tz = np.empty(Kb)
    Y = np.empty((m, Kb))
    G = np.empty((m, m))  # its lower triangle only is written and read
    floor = np.empty(m)
    ag = np.empty((nc, k))
    gh = np.empty((nc * k, k))
    coef = np.empty(m)
    bz = np.empty((nc, m))
    zr = np.empty(Kb)
    lev = np.empty(Kb)
    yi = np.empty(Kb)
    t = np.empty(k)
    lam = np.empty(m)
    acc = np.empty(Kb)
    # the rows go to out at their places, or (keep False: what the fits measure only) each in
    # turn to one scratch row
    row = out if keep else np.empty((len(targets), Kb))
    for o in range(start, stop):  # row r = order[o]: the caller's order, for the memory's sake
        r = order[o]
        w = centers[r]
        a0 = indptr[r]
        K = indptr[r + 1] - a0
        s0 = starts[r]  # row r's neighbours in indices; its outputs at indptr[r]
        b0 = a0 if keep else 0
        nbr = indices[s0:s0 + K]
        inv4h = 1.0 / (4.0 * hv[r])
        th_sum = 0.0
        for j in range(K):
            s = 0.0
            for a in range(d):
                X[j, a] = P[nbr[j], a] - P[w, a]
                s += X[j, a] * X[j, a]
            th[j] = math.exp(-s * inv4h)
            th_sum += th[j]
        _frame(P, w, nbr, th, normals[w if use_normals else 0], use_normals, B, C, ev, vec, v)
        rho2 = 0.0
        for j in range(K):
            s2 = 0.0
            for b in range(d):
                s = 0.0
                for a in range(d):
                    s += X[j, a] * B[b, a]
                if b < k:
                    U[b, j] = s
                    s2 += s * s
                else:
                    Z[b - k, j] = s
            rho2 = max(rho2, s2)
        rho = math.sqrt(rho2) if rho2 > 0.0 else 1.0
        for b in range(k):
            for j in range(K):
                U[b, j] /= rho
        for j in range(K):
            Phi[0, j] = 1.0
        for al in range(1, mb):
            pa, va = parent[al], var[al]
            for j in range(K):
                Phi[al, j] = Phi[pa, j] * U[va, j]
        _dots(Phi, th, nmom, K, mom)
        for al in range(m):
            for be in range(al + 1):
                G[al, be] = mom[pair[al, be]]
        # the right-hand sides of the height fits, Σ_j θ_j z_j Φ_α, for every degree at once
        for c in range(nc):
            for j in range(K):
                tz[j] = th[j] * Z[c, j]
            _dots(Phi, tz, m, K, bz[c])
        for al in range(m):  # a pivot must stay above this fraction of its diagonal entry
            floor[al] = PIVOT_TOL * G[al, al]
        good = cholesky(G, m, floor)
        for ti in range(len(targets)):
            q = targets[ti]
            while q >= 2 and count[q] > good:
                q -= 1
            if q < 2:
                used[ti, r] = -1
                for j in range(K):
                    row[ti, b0 + j] = 0.0
                continue
            used[ti, r] = q
            mq = count[q]
            # the graph z = g(u): its gradient a and Hessian gh at u = 0, in unscaled units
            ag[:, :] = 0.0
            gh[:, :] = 0.0  # ∂_ij g_c at row c·k + i
            res = 0.0
            for c in range(nc):
                for al in range(mq):
                    coef[al] = bz[c, al]
                chol_solve(G, coef, mq)
                for i in range(k):
                    ag[c, i] = coef[idx1[i]] / rho
                    for jj in range(k):
                        gh[c * k + i, jj] = coef[idx2[i, jj]] * (2.0 if i == jj else 1.0) / rho2
                for j in range(K):
                    zr[j] = Z[c, j]
                for al in range(mq):
                    ca = coef[al]
                    for j in range(K):
                        zr[j] -= ca * Phi[al, j]
                for j in range(K):
                    res += th[j] * zr[j] * zr[j]
            if not want_noise:
                resid[ti, r] = math.sqrt(res / (max(nc, 1) * th_sum))
            # E[Σθr²] = σ² (Σθ − Σ θ_j² Φ_j G⁻¹ Φ_jᵀ): the degrees of freedom the fit leaves
            # (Y: G's factor solved against Φ, by forward substitution for all neighbours at
            # once, over contiguous rows)
            dof = 0.0
            if want_noise:
                for j in range(K):
                    lev[j] = 0.0
                for i in range(mq):
                    for j in range(K):
                        yi[j] = Phi[i, j]
                    for q2 in range(i):  # (into yi: a row of Y of its own, the loop vectorizes)
                        g = G[i, q2]
                        for j in range(K):
                            yi[j] -= g * Y[q2, j]
                    g = 1.0 / G[i, i]  # (a product: a vector of divisions costs as much as the rest)
                    for j in range(K):
                        Y[i, j] = yi[j] * g
                        lev[j] += Y[i, j] * Y[i, j]
                for j in range(K):
                    dof += th[j] - th[j] * th[j] * lev[j]
                resid[ti, r] = math.sqrt(res / (nc * dof)) if nc > 0 and dof > 1e-3 * th_sum else (
                    0.0 if nc == 0 else np.inf)
            ks = 0.0
            for c in range(nc):
                for i in range(k):
                    for jj in range(k):
                        ks += gh[c * k + i, jj] * gh[c * k + i, jj]
            kap[ti, r] = math.sqrt(ks / k)
            # the metric G = I + Σ_c ∇g_c ∇g_cᵀ, factored in place; Gi = G⁻¹ column by column
            # (G ≥ I is positive definite)
            for i in range(k):
                for jj in range(k):
                    Lk[i, jj] = 1.0 if i == jj else 0.0
            for c in range(nc):
                for i in range(k):
                    for jj in range(k):
                        Lk[i, jj] += ag[c, i] * ag[c, jj]
            cholesky(Lk, k, kfloor)
            for jj in range(k):
                for i in range(k):
                    kcol[i] = 1.0 if i == jj else 0.0
                chol_solve(Lk, kcol, k)
                for i in range(k):
                    Gi[i, jj] = kcol[i]
            # Γ contracted with G^{ij}: v_l = G^{lm} Σ_c ∂_m g_c (G^{ij} ∂_ij g_c)
            t[:] = 0.0
            for c in range(nc):
                tr = 0.0
                for i in range(k):
                    for jj in range(k):
                        tr += Gi[i, jj] * gh[c * k + i, jj]
                for i in range(k):
                    t[i] += ag[c, i] * tr
            lam[:] = 0.0
            for i in range(k):
                for jj in range(k):
                    lam[idx2[i, jj]] += Gi[i, jj] * (2.0 if i == jj else 1.0) / rho2
                vl = 0.0
                for mm in range(k):
                    vl += Gi[i, mm] * t[mm]
                lam[idx1[i]] -= vl / rho
            chol_solve(G, lam, mq)
            s2 = 0.0
            acc[:K] = 0.0
            for al in range(mq):
                la = lam[al]
                for j in range(K):
                    acc[j] += Phi[al, j] * la
            for j in range(K):
                s = acc[j] * th[j]
                row[ti, b0 + j] = s
                s2 += s * s
            # the basis holds the constants, so the row sums to zero up to rounding: make it exact
            # on the centre's own entry (it is among the neighbours)
            tot_row = 0.0
            self_q = -1
            for j in range(K):
                tot_row += row[ti, b0 + j]
                if nbr[j] == w:
                    self_q = b0 + j
            if self_q >= 0:
                row[ti, self_q] -= tot_row
            amp[ti, r] = math.sqrt(s2)
            # probes: the row applied to the monomials of degree q + 1 and q + 2 (unscaled)
            for e in range(2):
                qq = q + 1 + e
                if qq > top:
                    bias[r, 2 * ti + e] = np.nan
                    continue
                pacc = 0.0
                for al in range(count[qq - 1], count[qq]):
                    s = 0.0
                    for j in range(K):
                        s += row[ti, b0 + j] * Phi[al, j]
                    pacc += s * s
                bias[r, 2 * ti + e] = math.sqrt(pacc) * rho ** qq


@jit()
def gather_columns(indices, starts, indptr, cols):  # pragma: no cover - compiled
    # cols[indptr[r] + j] = indices[starts[r] + j]: the columns of rows read from a wider table
    for r in range(len(indptr) - 1):
        a, b = indptr[r], starts[r]
        for j in range(indptr[r + 1] - a):
            cols[a + j] = indices[b + j]


@jit()
def copy_rows(rows, src_indptr, src_indices, src_data, indptr, indices, data):  # pragma: no cover - compiled
    # rows of one CSR matrix into the same rows of another whose indptr has room for them
    for r in rows:
        a = src_indptr[r]
        b = indptr[r]
        for i in range(src_indptr[r + 1] - a):
            indices[b + i] = src_indices[a + i]
            data[b + i] = src_data[a + i]


@jit()
def neighbour_medians(values, nb, skip_nan, out):  # pragma: no cover - compiled
    # out[i] = np.median(values[nb[i]]), or with skip_nan np.nanmedian (NaN where all are NaN):
    # the same numbers (the middle one, or the two middle ones' sum halved) without the
    # masked arrays nanmedian takes for short rows (5x slower than median)
    w = nb.shape[1]
    buf = np.empty(w)
    for i in range(len(out)):
        c = 0
        nan = False
        for j in range(w):
            x = values[nb[i, j]]
            if x != x:
                nan = True
                continue
            # insertion sort: a row holds a few neighbours
            p = c
            while p > 0 and buf[p - 1] > x:
                buf[p] = buf[p - 1]
                p -= 1
            buf[p] = x
            c += 1
        if c == 0 or (nan and not skip_nan):
            out[i] = np.nan
        elif c % 2:
            out[i] = buf[c // 2]
        else:
            out[i] = (buf[c // 2 - 1] + buf[c // 2]) / 2.0
