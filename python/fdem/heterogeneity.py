"""Spatially random rock strength: per-element factors on the tensile
strength and cohesion of a Mohr–Coulomb–Rankine rock, drawn from a seeded
Weibull or lognormal distribution of mean 1, independent per element or
correlated over a length (:meth:`fdem.Model.vary_strength`; docs/fracture.md,
"Heterogeneous rock").

Real rock is not uniformly strong: grains, flaws and cemented joints make
the strength vary from point to point, and it is that scatter which makes a
compression specimen fail by cracking (tension where stiff or strong
grains force the flow of weak ones around them) rather than by uniform
plastic flow (Weibull 1951; Tang 1997 for RFPA; FDEM peers such as Y-Geo
and Irazu offer the same).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["weibull_shape", "strength_factors", "DISTRIBUTIONS"]

#: The distributions of :func:`strength_factors`.
DISTRIBUTIONS = ("weibull", "lognormal")


def weibull_shape(cv: float) -> float:
    """The Weibull modulus k whose distribution has coefficient of variation
    ``cv``: ``cv² = Γ(1 + 2/k) / Γ(1 + 1/k)² − 1`` (solved by bisection on
    log k; cv from 0.01 to 2)."""
    if not 0.01 <= cv <= 2.0:
        raise ValueError(f"cv = {cv} must lie in [0.01, 2] (coefficient of variation of the strength)")

    def f(k: float) -> float:
        return math.gamma(1 + 2 / k) / math.gamma(1 + 1 / k) ** 2 - 1 - cv * cv

    lo, hi = math.log(0.3), math.log(200.0)  # cv 3.1 to 0.0064
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(math.exp(mid)) > 0:
            lo = mid
        else:
            hi = mid
    return math.exp(0.5 * (lo + hi))


def _normal_cdf(z: NDArray[np.float64]) -> NDArray[np.float64]:
    """Φ(z), the standard normal distribution function, elementwise."""
    erf = np.vectorize(math.erf, otypes=[float])
    return np.asarray(0.5 * (1.0 + erf(z / math.sqrt(2.0))), dtype=float)


def _gaussian_field(points: NDArray[np.float64], length: float, rng: np.random.Generator) -> NDArray[np.float64]:
    """A standard normal random field at ``points`` (n, 2) with the
    correlation ``exp(−d²/ℓ²)``: white noise on a grid of spacing ℓ/4
    smoothed by a Gaussian kernel of standard deviation ℓ/2 (the
    convolution of two such kernels is the correlation), normalised to
    unit variance, read bilinearly."""
    h = 0.25 * length
    s = 0.5 * length
    lo = points.min(axis=0) - 3 * s
    hi = points.max(axis=0) + 3 * s
    shape = np.ceil((hi - lo) / h).astype(int) + 2
    if int(np.prod(shape)) > 50_000_000:
        raise ValueError(f"correlation_length = {length} is too short for the model's extent (grid {shape.tolist()})")
    noise = rng.standard_normal(tuple(shape))
    r = int(np.ceil(3 * s / h))
    u = np.arange(-r, r + 1) * h
    kernel = np.exp(-0.5 * (u / s) ** 2)
    field = np.apply_along_axis(lambda v: np.convolve(v, kernel, mode="same"), 0, noise)
    field = np.apply_along_axis(lambda v: np.convolve(v, kernel, mode="same"), 1, field)
    field /= math.sqrt(float(np.sum(kernel**2)) ** 2)  # unit variance away from the grid's edges
    g = (points - lo) / h
    i = np.floor(g).astype(int)
    f = g - i
    a = field[i[:, 0], i[:, 1]] * (1 - f[:, 0]) + field[i[:, 0] + 1, i[:, 1]] * f[:, 0]
    b = field[i[:, 0], i[:, 1] + 1] * (1 - f[:, 0]) + field[i[:, 0] + 1, i[:, 1] + 1] * f[:, 0]
    return a * (1 - f[:, 1]) + b * f[:, 1]


def strength_factors(
    points: NDArray[np.float64],
    *,
    cv: float,
    distribution: str = "weibull",
    correlation_length: float | None = None,
    seed: int = 0,
    levels: int = 64,
) -> NDArray[np.float64]:
    """Strength factors of mean 1 at ``points`` (n, 2; element centroids, m).

    A standard normal value per point (independent, or a Gaussian random
    field with correlation ``exp(−d²/ℓ²)`` for ``correlation_length`` ℓ)
    becomes a probability u = Φ(z), which picks one of ``levels``
    equiprobable classes of the distribution; a class's factor is the
    distribution's quantile at its middle probability. ``"weibull"``:
    modulus k from ``cv`` (:func:`weibull_shape`), scale 1/Γ(1 + 1/k);
    ``"lognormal"``: exp(σ z − σ²/2) with σ² = ln(1 + cv²). The classes
    keep the number of materials small (a model carries one per class);
    with 64 the class means match the distribution's mean within 0.1% and
    its cv within 2%. The same seed gives the same factors on any machine
    (numpy's PCG64).
    """
    if distribution not in DISTRIBUTIONS:
        raise ValueError(f"distribution must be one of {DISTRIBUTIONS}, not {distribution!r}")
    if not 2 <= int(levels) <= 4096:
        raise ValueError(f"levels = {levels} must lie in [2, 4096]")
    rng = np.random.default_rng(int(seed))
    if correlation_length is None:
        z = rng.standard_normal(len(points))
    else:
        if not correlation_length > 0:
            raise ValueError(f"correlation_length = {correlation_length} must be positive (m)")
        z = _gaussian_field(np.asarray(points, dtype=float), float(correlation_length), rng)
    u = _normal_cdf(z)
    k = np.minimum((u * levels).astype(int), levels - 1)
    mid = (np.arange(levels) + 0.5) / levels
    if distribution == "weibull":
        shape = weibull_shape(cv)
        scale = 1.0 / math.gamma(1 + 1 / shape)
        classes = scale * (-np.log1p(-mid)) ** (1 / shape)
    else:
        sigma = math.sqrt(math.log1p(cv * cv))
        zs = np.array([_normal_quantile(p) for p in mid])
        classes = np.exp(sigma * zs - 0.5 * sigma * sigma)
    classes /= classes.mean()  # the classes' own mean is exactly 1
    return classes[k]


def _normal_quantile(p: float) -> float:
    """Φ⁻¹(p) by bisection on math.erf (p in (0, 1))."""
    lo, hi = -10.0, 10.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if 0.5 * (1 + math.erf(mid / math.sqrt(2))) < p:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
