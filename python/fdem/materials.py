"""Material descriptions: plain immutable values checked on construction."""

from __future__ import annotations

from dataclasses import dataclass

from ._checks import number

__all__ = ["Elastic"]


@dataclass(frozen=True)
class Elastic:
    """Isotropic linear elasticity in plane strain (``ε_zz = 0``, ``σ_zz``
    tracked).

    Parameters
    ----------
    E : float
        Young's modulus (Pa), ``E > 0``.
    nu : float
        Poisson's ratio, ``-1 < nu < 0.5``.
    rho : float
        Density (kg/m³), ``rho > 0``.

    Raises
    ------
    ValueError
        Naming the parameter that is out of range.
    """

    E: float
    nu: float
    rho: float

    def __post_init__(self) -> None:
        for name in ("E", "nu", "rho"):
            object.__setattr__(self, name, number(name, getattr(self, name)))
        if self.E <= 0:
            raise ValueError(f"E = {self.E} must be positive (Young's modulus, Pa)")
        if not -1.0 < self.nu < 0.5:
            raise ValueError(f"nu = {self.nu} must lie in (-1, 0.5) (Poisson's ratio)")
        if self.rho <= 0:
            raise ValueError(f"rho = {self.rho} must be positive (density, kg/m³)")

    @property
    def shear_modulus(self) -> float:
        """``G = E / (2(1 + ν))`` (Pa)."""
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def lame_lambda(self) -> float:
        """``λ = E ν / ((1 + ν)(1 − 2ν))`` (Pa)."""
        return self.E * self.nu / ((1.0 + self.nu) * (1.0 - 2.0 * self.nu))

    @property
    def p_wave_speed(self) -> float:
        """Plane-strain P-wave speed ``√((λ + 2G)/ρ)`` (m/s)."""
        return float(((self.lame_lambda + 2.0 * self.shear_modulus) / self.rho) ** 0.5)

    @property
    def s_wave_speed(self) -> float:
        """Shear-wave speed ``√(G/ρ)`` (m/s)."""
        return float((self.shear_modulus / self.rho) ** 0.5)

    def _kernel_row(self) -> list[float]:
        return [self.rho, self.E, self.nu]
