#!/usr/bin/env python3
"""Computes the RGB -> spectrum upsampling basis of `crates/spectrum/src/upsample.rs`.

Three spectra b_r, b_g, b_b on the 5 nm grid 360..830 nm (95 nodes, linearly interpolated
between nodes), the solution of the quadratic programme

    minimise   sum_c sum_i (b_c[i-1] - 2 b_c[i] + b_c[i+1])^2          (smoothness)
    subject to b_r + b_g + b_b = 1 at every node                       (white -> 1)
               integral b_c D65 cmf_k dl / integral D65 ybar dl = M[k][c]
                   for c in {r, g}, k in {X, Y, Z}                     (colour of the primaries)
               b >= 0

where M is linear sRGB -> XYZ derived from the sRGB primaries and the white point of the
integrated tabulated D65 (as `spectrum::cie::SRGB_TO_XYZ`). The blue column's constraints
follow from the others (the sum is 1, and M (1,1,1) is the white point), so they are left out
to keep the constraint matrix of full rank. The integrals are the exact integrals of the
products of the three piecewise-linear interpolants (cubic on each 5 nm interval: Simpson's
rule is exact), computed with the tables rounded to float32 as the Rust code uses them.

Method: ADMM (x = z splitting, z >= 0) to find the active set, then an active-set polish that
solves the KKT system exactly and checks the signs of the multipliers. numpy only.

Usage: python3 crates/spectrum/tools/basis.py [--write]
  prints the statistics; with --write replaces the generated table in src/upsample.rs.
"""

import pathlib
import re
import sys

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
CIE_RS = HERE.parent / "src" / "cie.rs"
UPSAMPLE_RS = HERE.parent / "src" / "upsample.rs"
N = 95
H = 5.0


def read_table(name):
    """A 95-entry f64 table of cie.rs, rounded to float32 (as the Rust interpolants use it)."""
    text = CIE_RS.read_text()
    m = re.search(r"pub const " + name + r": \[f64; TABLE_LEN\] = \[(.*?)\];", text, re.S)
    vals = [float(v) for v in m.group(1).replace("\n", " ").split(",") if v.strip()]
    assert len(vals) == N, (name, len(vals))
    return np.array(vals, dtype=np.float32).astype(np.float64)


def srgb_to_xyz(white):
    prim = np.array([[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]])
    p = np.array([[x / y, 1.0, (1 - x - y) / y] for x, y in prim]).T  # columns = primaries
    s = np.linalg.solve(p, white)
    return p * s


def triple_weights(d, m):
    """w such that integral b d m dl = w . b for b, d, m piecewise linear on the grid (exact)."""
    w = np.zeros(N)
    for i in range(N - 1):
        # Simpson on the interval (exact for cubics), in t in [0, 1].
        for t, sw in ((0.0, 1.0), (0.5, 4.0), (1.0, 1.0)):
            dm = (d[i] * (1 - t) + d[i + 1] * t) * (m[i] * (1 - t) + m[i + 1] * t)
            w[i] += H * sw / 6.0 * (1 - t) * dm
            w[i + 1] += H * sw / 6.0 * t * dm
    return w


def product_integral(a, b):
    return sum(H * (2 * a[i] * b[i] + a[i] * b[i + 1] + a[i + 1] * b[i] + 2 * a[i + 1] * b[i + 1]) / 6
               for i in range(N - 1))


def solve_eqp(P, A, b, active):
    """min 1/2 x'Px s.t. Ax = b, x[active] = 0: returns x, nu (for A), mu (bound multipliers)."""
    n = P.shape[0]
    E = np.zeros((len(active), n))
    E[np.arange(len(active)), active] = 1.0
    C = np.vstack([A, E])
    K = np.block([[P, C.T], [C, np.zeros((C.shape[0], C.shape[0]))]])
    rhs = np.concatenate([np.zeros(n), b, np.zeros(len(active))])
    sol = np.linalg.lstsq(K, rhs, rcond=None)[0]
    x = sol[:n]
    lam = sol[n:]
    # Stationarity: P x + A' nu + E' lam = 0, with the bound multiplier mu = -lam >= 0.
    return x, lam[: A.shape[0]], -lam[A.shape[0]:]


def main():
    xbar, ybar, zbar, d65 = (read_table(n) for n in ("CIE_X", "CIE_Y", "CIE_Z", "D65_TABLE"))
    cmf = [xbar, ybar, zbar]
    d65_xyz = np.array([product_integral(d65, c) for c in cmf])
    d65_y = d65_xyz[1]
    white = d65_xyz / d65_y
    M = srgb_to_xyz(white)

    # Smoothness: second differences of each basis function.
    D = np.zeros((N - 2, N))
    for i in range(N - 2):
        D[i, i : i + 3] = [1.0, -2.0, 1.0]
    Q = D.T @ D
    P = np.kron(np.eye(3), Q)

    rows, rhs = [], []
    # Partition of unity.
    for i in range(N):
        r = np.zeros(3 * N)
        r[[i, N + i, 2 * N + i]] = 1.0
        rows.append(r)
        rhs.append(1.0)
    colour_w = [triple_weights(d65, c) / d65_y for c in cmf]
    for c in range(2):
        for k in range(3):
            r = np.zeros(3 * N)
            r[c * N : (c + 1) * N] = colour_w[k]
            rows.append(r)
            rhs.append(M[k, c])
    A = np.array(rows)
    b = np.array(rhs)

    # ADMM.
    rho = 1.0
    n = 3 * N
    K = np.block([[P + rho * np.eye(n), A.T], [A, np.zeros((len(b), len(b)))]])
    Kinv = np.linalg.pinv(K)
    z = np.full(n, 1.0 / 3.0)
    u = np.zeros(n)
    for it in range(20000):
        sol = Kinv @ np.concatenate([rho * (z - u), b])
        x = sol[:n]
        z_old = z
        z = np.maximum(0.0, x + u)
        u += x - z
        if it % 100 == 0 and np.abs(x - z).max() < 1e-12 and np.abs(z - z_old).max() < 1e-12:
            break
    print(f"ADMM: {it + 1} iterations, |x - z| = {np.abs(x - z).max():.2e}")

    # Active-set polish.
    active = sorted(np.flatnonzero(z < 1e-9))
    for step in range(200):
        x, nu, mu = solve_eqp(P, A, b, np.array(active, dtype=int))
        free = np.setdiff1d(np.arange(n), active)
        worst_x = free[np.argmin(x[free])] if len(free) else None
        if worst_x is not None and x[worst_x] < -1e-13:
            active = sorted(set(active) | {int(i) for i in free if x[i] < -1e-13})
            continue
        if len(active) and mu.min() < -1e-12:
            active.remove(active[int(np.argmin(mu))])
            continue
        break
    else:
        sys.exit("active-set polish did not converge")
    x[active] = 0.0
    x = np.maximum(x, 0.0)
    print(f"polish: {step + 1} steps, {len(active)} active bounds, min multiplier "
          f"{mu.min() if len(mu) else 0:.3e}")

    basis = x.reshape(3, N)
    print(f"equality residual {np.abs(A @ x - b).max():.2e}; partition of unity "
          f"{np.abs(basis.sum(0) - 1).max():.2e}")
    print(f"objective (sum of squared second differences) {x @ P @ x:.6e}")
    for c, name in enumerate("rgb"):
        d2 = D @ basis[c]
        print(f"b_{name}: min {basis[c].min():.6f} max {basis[c].max():.6f} "
              f"max |second difference| {np.abs(d2).max():.6f} sum sq {d2 @ d2:.6e} "
              f"zeros {int((basis[c] == 0).sum())}")
    # Colour of each basis function (including blue, which was not constrained directly).
    got = np.array([[colour_w[k] @ basis[c] for c in range(3)] for k in range(3)])
    print(f"max |XYZ(b_c) - M[:, c]| = {np.abs(got - M).max():.2e}")

    # float32 table for Rust.
    b32 = basis.astype(np.float32)
    got32 = np.array([[colour_w[k] @ b32[c].astype(np.float64) for c in range(3)] for k in range(3)])
    print(f"after rounding to f32: max |XYZ - M| = {np.abs(got32 - M).max():.2e}, partition of unity "
          f"{np.abs(b32.astype(np.float64).sum(0) - 1).max():.2e}")

    if "--write" in sys.argv:
        lines = ["// BEGIN GENERATED by tools/basis.py: do not edit.",
                 "/// The basis `[b_r, b_g, b_b]` at 360, 365, …, 830 nm (unitless).",
                 "#[rustfmt::skip]",
                 "const BASIS: [[f32; 3]; TABLE_LEN] = ["]
        for i in range(N):
            vals = ", ".join(fmt32(v) for v in b32[:, i])
            lines.append(f"    [{vals}], // {360 + 5 * i} nm")
        lines.append("];")
        lines.append("// END GENERATED")
        text = UPSAMPLE_RS.read_text()
        new = re.sub(r"// BEGIN GENERATED.*?// END GENERATED", "\n".join(lines), text, flags=re.S)
        assert new != text or "BEGIN GENERATED" in text
        UPSAMPLE_RS.write_text(new)
        print(f"wrote {UPSAMPLE_RS}")


def fmt32(v):
    """Shortest decimal that reads back as the same float32, always with a decimal point or exponent."""
    v = np.float32(v)
    if v == 0:
        return "0.0"
    for digits in range(6, 10):
        s = f"{float(v):.{digits}g}"
        if np.float32(float(s)) == v:
            break
    if "." not in s and "e" not in s:
        s += ".0"
    return s


if __name__ == "__main__":
    main()
