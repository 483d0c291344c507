"""Reference illuminance on a sphere resting on a Lambertian plane under overhead parallel
light: the test case of Ward, Rubinstein & Clear (1988), §4, direct light plus the
first diffuse reflection.

Geometry (metres): a sphere of radius 1 centred at C = (0, 0, 1) touches the plane
z = 0 at the origin.  A point on the sphere is P = C + n, n = (cos γ cos φ, cos γ sin φ,
sin γ) its outward normal, γ the elevation above the horizontal through the centre
(the paper's "angle below the horizontal", with the opposite sign).  The light is
parallel and vertical: E0 [lux] on a surface facing it.  Both surfaces are Lambertian
with reflectance ρ.

**Direct light.**  E_dir = E0 max(0, sin γ): the upper half faces the light and nothing
shades it; the lower half faces away.

**First reflection.**  The plane is lit at E0 everywhere except in the sphere's shadow,
the vertical projection of the sphere: the unit disc D = {x² + y² < 1, z = 0}.  Its
luminance is L = ρE0/π outside D and 0 inside.  (Light reflected by the sphere onto the
plane is a second reflection and does not count.)  A point of a convex body sees
exactly the half-space in front of its tangent plane, unobstructed, so it sees the
part of the plane in the half-plane H = {Q : (Q − P)·n > 0, z = 0}.  With
Φ(A) = ∫_A cos θ dω, the projected solid angle of a region A of the plane seen from P
[sr], the first reflection gives

    E_ind = L · Φ(H \\ D) = (ρE0/π) · [Φ(H) − Φ(H ∩ D)],    Φ(H) = π (1 − sin γ)/2,

Φ(H) being the projected solid angle of everything below the horizon seen by a
surface tilted by 90° − γ from the vertical.

* Upper half (γ ≥ 0): for Q ∈ D, (Q − P)·n = q·n_xy − 1 − sin γ < cos γ − 1 − sin γ ≤ 0,
  so H ∩ D = ∅ and the closed form is  E = E0 sin γ + ρE0 (1 − sin γ)/2.
* Lower half (γ < 0): H cuts D along the line x' = c, x' the horizontal coordinate
  along n's azimuth and c = (1 + sin γ)/cos γ < 1, leaving a circular segment
  H ∩ D.  Φ(H ∩ D) is found by the contour-integral form of the projected solid angle
  (Stokes' theorem applied to the form factor; Sparrow, "A New and Simpler
  Formulation for Radiative Angle Factors", J. Heat Transfer 85, 1963):

      Φ(A) = ½ |∮_∂A n · (r × dr) / |r|²|,   r = Q − P,

  valid when all of A lies in front of the tangent plane.  ∂(H ∩ D) is the chord,
  whose term is Lambert's closed form for a straight edge, ½ · angle(a, b) ·
  n·(a × b)/|a × b|, a and b the chord's ends seen from P, plus the arc
  Q(ψ) = (cos ψ, sin ψ, 0), |ψ| ≤ arccos c, a smooth 1-D integral done by
  Gauss–Legendre quadrature, doubling the nodes until two successive estimates agree to
  1e-13 (absolute, in sr; the result's relative accuracy is stated by
  :func:`quadrature_error`).  So  E = (ρE0/π) [π(1 − sin γ)/2 − Φ(H ∩ D)],  which → 0 at the
  contact point (γ → −90°), where H ∩ D fills the whole view.

**Finite plane.**  A simulation has a square plane of half-width W.  What it lacks is
L · Φ(H \\ square) ≤ L · Φ(H \\ disc_W), disc_W the inscribed disc of radius W, which
the same contour code gives (:func:`truncation_deficit`).  For large W it is about
(2ρE0/π) (1 + sin γ) cos γ / W: a tilted surface sees the far plane up to its horizon,
so the deficit falls only as 1/W.

The sun of the simulations is a disc of 6.8e-5 sr, not a point: the shadow's edge is
blurred over about 1 cm around the unit circle, symmetrically, which changes Φ by
far less than 1e-5 of E; the reference ignores it.
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial.legendre import leggauss

__all__ = ["illuminance", "reflected_fraction", "segment_projected_solid_angle", "truncation_deficit",
           "quadrature_error", "monte_carlo_illuminance", "RHO", "E0"]

#: Reflectance of sphere and plane, and the light's normal illuminance [lux] (paper §4).
RHO = 0.7
E0 = 1000.0
#: Convergence target of the arc quadrature [sr, absolute].
QUAD_TOLERANCE = 1e-13
_MAX_NODES = 4096


def _lambert_edge(a, b, n):
    """½ · angle(a, b) · n·(a × b)/|a × b|: one straight edge's term of the contour
    integral (Lambert's polygon formula).  a, b : (k, 3) ends seen from P; n : (k, 3)."""
    cross = np.cross(a, b)
    norm = np.linalg.norm(cross, axis=1)
    angle = np.arctan2(norm, np.einsum("ij,ij->i", a, b))
    with np.errstate(invalid="ignore", divide="ignore"):
        term = np.where(norm > 0, angle * np.einsum("ij,ij->i", n, cross) / np.where(norm > 0, norm, 1.0), 0.0)
    return 0.5 * term


def _arc(P, n, radius, lo, hi, nodes):
    """½ ∫_lo^hi n · (r × dQ/dψ) / |r|² dψ over Q(ψ) = radius (cos ψ, sin ψ, 0),
    r = Q − P, by Gauss–Legendre with ``nodes`` nodes.  P, n : (k, 3); lo, hi : (k,)."""
    x, w = leggauss(nodes)
    half = 0.5 * (hi - lo)
    psi = 0.5 * (hi + lo)[:, None] + half[:, None] * x[None, :]           # (k, m)
    Q = np.stack([radius * np.cos(psi), radius * np.sin(psi), np.zeros_like(psi)], axis=-1)
    T = np.stack([-radius * np.sin(psi), radius * np.cos(psi), np.zeros_like(psi)], axis=-1)
    r = Q - P[:, None, :]
    f = np.einsum("kx,kmx->km", n, np.cross(r, T)) / np.einsum("kmx,kmx->km", r, r)
    return 0.5 * half * (f @ w)


def segment_projected_solid_angle(P, n, radius=1.0, return_error=False):
    """Φ(H ∩ disc) [sr]: projected solid angle, seen from points P with unit normals n
    whose horizontal part points along +x (n_y = 0), of the part of the disc
    x² + y² < radius², z = 0 that lies in front of their tangent planes.

    P, n : (k, 3) with P_z > 0.  Returns (k,) values; with ``return_error`` also the
    last change of the doubling Gauss–Legendre quadrature (k,) [sr].
    """
    P = np.atleast_2d(np.asarray(P, np.float64))
    n = np.atleast_2d(np.asarray(n, np.float64))
    if np.any(np.abs(n[:, 1]) > 1e-12):
        raise ValueError("normals must lie in the xz-plane (n_y = 0)")
    k = len(P)
    pn = np.einsum("ij,ij->i", P, n)                   # front: n_x x > P·n on z = 0
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(n[:, 0] > 0, pn / np.where(n[:, 0] > 0, n[:, 0], 1.0),
                     np.where(pn < 0, -np.inf, np.inf))
    full = c <= -radius
    part = (c > -radius) & (c < radius)
    phi0 = np.where(full, np.pi, np.where(part, np.arccos(np.clip(c / radius, -1.0, 1.0)), 0.0))
    result = np.zeros(k)
    error = np.zeros(k)
    use = np.flatnonzero(full | part)
    if len(use):
        Pu, nu, p0 = P[use], n[use], phi0[use]
        # the chord from Q(φ0) back to Q(−φ0) (absent for a full disc)
        a = np.stack([radius * np.cos(p0), radius * np.sin(p0), np.zeros_like(p0)], axis=1) - Pu
        b = np.stack([radius * np.cos(p0), -radius * np.sin(p0), np.zeros_like(p0)], axis=1) - Pu
        chord = np.where(full[use], 0.0, _lambert_edge(a, b, nu))
        nodes = 32
        prev = _arc(Pu, nu, radius, -p0, p0, nodes)
        while True:
            nodes *= 2
            cur = _arc(Pu, nu, radius, -p0, p0, nodes)
            change = np.abs(cur - prev)
            prev = cur
            if np.all(change < QUAD_TOLERANCE) or nodes >= _MAX_NODES:
                break
        result[use] = np.abs(cur + chord)
        error[use] = change
    return (result, error) if return_error else result


def _frame(gamma):
    """Points and normals on the sphere at elevations ``gamma`` [rad], azimuth 0."""
    g = np.atleast_1d(np.asarray(gamma, np.float64))
    n = np.stack([np.cos(g), np.zeros_like(g), np.sin(g)], axis=1)
    return n + np.array([0.0, 0.0, 1.0]), n


def reflected_fraction(gamma):
    """E_ind / (ρE0) = Φ(H \\ D)/π at elevations ``gamma`` [rad]: the first reflection
    from an infinite plane with the unit shadow disc, as a fraction of ρE0."""
    g = np.atleast_1d(np.asarray(gamma, np.float64))
    out = 0.5 * (1.0 - np.sin(g))                      # Φ(H)/π, the whole visible plane
    low = np.flatnonzero(g < 0)
    if len(low):
        P, n = _frame(g[low])
        out[low] -= segment_projected_solid_angle(P, n) / np.pi
    return out


def illuminance(gamma, E0=E0, rho=RHO):
    """Illuminance [lux] on the sphere at elevations ``gamma`` [rad]: E0 max(0, sin γ)
    + ρE0 · Φ(H \\ D)/π (closed form for γ ≥ 0, contour quadrature below)."""
    g = np.atleast_1d(np.asarray(gamma, np.float64))
    return E0 * np.maximum(np.sin(g), 0.0) + rho * E0 * reflected_fraction(g)


def quadrature_error(gamma, E0=E0, rho=RHO):
    """Relative size of the last quadrature change, |ΔΦ| ρE0/π / E, at ``gamma`` [rad]
    (0 for γ ≥ 0, where the closed form holds)."""
    g = np.atleast_1d(np.asarray(gamma, np.float64))
    out = np.zeros_like(g)
    low = np.flatnonzero(g < 0)
    if len(low):
        P, n = _frame(g[low])
        _, err = segment_projected_solid_angle(P, n, return_error=True)
        out[low] = err * rho * E0 / np.pi / illuminance(g[low], E0, rho)
    return out


def truncation_deficit(gamma, half_width, E0=E0, rho=RHO):
    """Upper bound [lux] of the light a square plane of half-width ``half_width`` [m]
    (centred on the contact point) fails to reflect onto the sphere at ``gamma`` [rad],
    compared with the infinite plane: ρE0/π · Φ(H \\ disc_W), disc_W the inscribed disc.
    Valid for half_width > 1 (the shadow lies inside the square)."""
    g = np.atleast_1d(np.asarray(gamma, np.float64))
    P, n = _frame(g)
    inside = segment_projected_solid_angle(P, n, radius=float(half_width))
    return rho * E0 / np.pi * np.maximum(np.pi * 0.5 * (1.0 - np.sin(g)) - inside, 0.0)


def monte_carlo_illuminance(gamma, samples, rng, E0=E0, rho=RHO):
    """Brute-force check of :func:`illuminance`, independent of the contour formula:
    cosine-distributed directions from each point, E_ind = ρE0 · (fraction that reaches
    the lit plane, z = 0 outside the unit disc), plus the direct term.  Returns
    (estimate, standard error) [lux], each (k,)."""
    g = np.atleast_1d(np.asarray(gamma, np.float64))
    P, n = _frame(g)
    est, se = np.zeros(len(g)), np.zeros(len(g))
    for i in range(len(g)):
        u1, u2 = rng.random(samples), rng.random(samples)
        s, phi = np.sqrt(u1), 2.0 * np.pi * u2
        local = np.stack([s * np.cos(phi), s * np.sin(phi), np.sqrt(1.0 - u1)], axis=1)
        t = np.cross(n[i], [0.0, 1.0, 0.0])
        t /= np.linalg.norm(t)
        b = np.cross(n[i], t)
        d = local[:, :1] * t + local[:, 1:2] * b + local[:, 2:3] * n[i]
        down = d[:, 2] < 0
        tt = np.where(down, -P[i, 2] / np.where(down, d[:, 2], -1.0), np.inf)
        Q = P[i] + tt[:, None] * d
        lit = down & (Q[:, 0] ** 2 + Q[:, 1] ** 2 >= 1.0)
        p = lit.mean()
        est[i] = E0 * max(np.sin(g[i]), 0.0) + rho * E0 * p
        se[i] = rho * E0 * np.sqrt(p * (1.0 - p) / samples)
    return est, se
