"""Material descriptions: plain immutable values checked on construction."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ._checks import number
from .errors import warn_implausible

__all__ = ["Elastic", "MohrCoulombRankine", "GII_PER_GF", "PETERSSON_KINK"]

#: The default ratio of the bonds' mode-II to mode-I fracture energy: 1, the
#: single fracture energy of Munjiza's Y code (Munjiza 2004, *The combined
#: finite-discrete element method*, ch. 7). Rock's mode-II toughness measured
#: in punch-through shear tests is about twice its mode-I toughness or more
#: (Backers, Stephansson & Rybacki 2002, Int. J. Rock Mech. Min. Sci. 39,
#: 755–769), four times the energy; give ``GII`` where it is known. It
#: decides how brittle a compressed specimen is: a heterogeneous UCS specimen
#: softens to 44% of its peak at 4 times its yield strain with ``GII = Gf``
#: and to 75% with ``4 Gf`` (docs/fracture.md, "Mixed-mode bonds").
GII_PER_GF = 1.0

#: The kink ``(s_k, F_k)`` of Petersson's (1981) bilinear softening curve
#: for concrete, ``softening="bilinear"``: ``ft/3`` at ``0.8 Gf/ft`` with
#: ``w_c = 3.6 Gf/ft``.
PETERSSON_KINK = (1.0 / 3.0, 2.0 / 9.0)


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
        if self.E < 1e6:
            warn_implausible(
                f"E = {self.E:g} Pa is below 1 MPa: Young's modulus is in Pa (30 GPa is 30e9), not MPa or GPa"
            )
        if self.rho < 100.0:
            warn_implausible(f"rho = {self.rho:g} kg/m³ is below 100: density is in kg/m³ (2.7 t/m³ is 2700)")

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

    @property
    def plane_strain_modulus(self) -> float:
        """``E' = E / (1 − ν²)`` (Pa)."""
        return self.E / (1.0 - self.nu**2)

    def _kernel_dict(self) -> dict[str, Any]:
        return {"kind": "elastic", "rho": self.rho, "E": self.E, "nu": self.nu}


@dataclass(frozen=True)
class MohrCoulombRankine(Elastic):
    """Mohr–Coulomb shear failure (perfectly plastic, non-associated) with a
    Rankine tension cut-off softening to zero over the fracture energy,
    linearly by default (Ecsi & Élesztős 2003, appendices A–C).

    Parameters
    ----------
    E, nu, rho : float
        Elastic constants and density, as for :class:`Elastic`.
    c : float
        Cohesion (Pa), ``c >= 0``.
    phi : float
        Friction angle (degrees), ``0 <= phi < 90``.
    psi : float
        Dilation angle (degrees), ``0 <= psi <= phi``.
    ft : float
        Tensile strength (Pa), ``0 < ft <= c cot(phi)``.
    Gf : float
        Fracture energy (N/m), ``Gf > 0``: mode I, of the crack band and of
        the cohesive bonds' opening.
    GII : float, optional
        Mode-II fracture energy (N/m) of the cohesive bonds across young
        cracks: what a bond dissipates in pure slip (docs/fracture.md,
        "Mixed-mode bonds"). Default ``Gf`` (:data:`GII_PER_GF`, where the
        choice is discussed).
    crack_band : {"oliver", "equivalent"}
        How the crack-band width ``h_c`` is measured: the element's width along
        σ1 when it first reaches ``ft`` (default; Oliver 1989), or the paper's
        ``√(4A/π)`` (about 20% too much dissipation for a band one element wide).
    softening : {"linear", "bilinear"} or (float, float)
        Shape of the tensile softening curve ``σ = ft s(w / w_c)`` with
        ``Gf = ft w_c ∫s`` (docs/fracture.md, "Softening laws"): ``"linear"``
        (default, the paper's: ``w_c = 2 Gf / ft``), ``"bilinear"``
        (Petersson 1981 for concrete: ``ft/3`` at ``0.8 Gf/ft``, zero at
        ``3.6 Gf/ft``), or a bilinear curve's kink ``(s_k, F_k)``: traction
        ``s_k ft`` at opening ``F_k w_c``, both in (0, 1). The crack band
        and the cohesive bonds follow the same curve.

    Notes
    -----
    With linear softening the softening modulus is ``H = h_c ft² / (2 Gf)``;
    an element wider than the snap-back limit (:attr:`snap_back_size`,
    ``2 E' Gf / ft²`` for linear softening) is rejected when the model is run.
    Table 1 of the paper: ``MohrCoulombRankine(E=60e9, nu=0.25, rho=3100,
    c=8e6, phi=55, psi=9, ft=1e6, Gf=70)``.
    """

    c: float = 0.0
    phi: float = 0.0
    psi: float = 0.0
    ft: float = 0.0
    Gf: float = 0.0
    crack_band: str = "oliver"
    GII: float | None = None
    softening: str | tuple[float, float] = "linear"

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("c", "phi", "psi", "ft", "Gf"):
            object.__setattr__(self, name, number(name, getattr(self, name)))
        if self.c < 0:
            raise ValueError(f"c = {self.c} must be >= 0 (cohesion, Pa)")
        if not 0 <= self.phi < 90:
            raise ValueError(f"phi = {self.phi} must lie in [0, 90) degrees (friction angle)")
        if not 0 <= self.psi < 90:
            raise ValueError(f"psi = {self.psi} must lie in [0, 90) degrees (dilation angle)")
        if 0 < self.phi < 1:
            warn_implausible(
                f"phi = {self.phi:g} degrees: angles are in degrees ({self.phi:g} rad would be "
                f"{math.degrees(self.phi):.1f} degrees)"
            )
        for name in ("c", "ft"):
            value = getattr(self, name)
            if 0 < value < 1e3:
                warn_implausible(f"{name} = {value:g} Pa is below 1 kPa: strengths are in Pa (5 MPa is 5e6)")
        if self.psi > self.phi:
            raise ValueError(f"psi = {self.psi} must not exceed phi = {self.phi} (dilation above friction)")
        if self.ft <= 0:
            raise ValueError(f"ft = {self.ft} must be positive (tensile strength, Pa)")
        if self.phi > 0 and self.ft > self.c / math.tan(math.radians(self.phi)) * (1 + 1e-12):
            apex = self.c / math.tan(math.radians(self.phi))
            raise ValueError(f"ft = {self.ft} must not exceed c*cot(phi) = {apex:.6g} Pa (the Mohr-Coulomb apex)")
        if self.Gf <= 0:
            raise ValueError(f"Gf = {self.Gf} must be positive (fracture energy, N/m)")
        if self.GII is not None:
            object.__setattr__(self, "GII", number("GII", self.GII))
            if self.GII <= 0:
                raise ValueError(f"GII = {self.GII} must be positive (mode-II fracture energy, N/m)")
        if self.crack_band not in ("oliver", "equivalent"):
            raise ValueError(f"crack_band = {self.crack_band!r} must be 'oliver' or 'equivalent'")
        if isinstance(self.softening, str):
            if self.softening not in ("linear", "bilinear"):
                raise ValueError(f"softening = {self.softening!r} must be 'linear', 'bilinear' or a kink (s_k, F_k)")
        else:
            try:
                kink = tuple(number("softening", v) for v in self.softening)
            except TypeError:
                kink = ()
            if len(kink) != 2 or not all(0 < v < 1 for v in kink):
                raise ValueError(
                    f"softening = {self.softening!r} must be 'linear', 'bilinear' or a kink (s_k, F_k) "
                    "with both in (0, 1): traction s_k ft at opening F_k w_c"
                )
            object.__setattr__(self, "softening", kink)

    @property
    def ucs(self) -> float:
        """Uniaxial compressive strength ``2 c cos φ / (1 − sin φ)`` (Pa)."""
        p = math.radians(self.phi)
        return 2 * self.c * math.cos(p) / (1 - math.sin(p))

    @property
    def n_phi(self) -> float:
        """``N_φ = (1 + sin φ) / (1 − sin φ)``: slope of the triaxial line."""
        s = math.sin(math.radians(self.phi))
        return (1 + s) / (1 - s)

    @property
    def n_psi(self) -> float:
        """``N_ψ = (1 + sin ψ) / (1 − sin ψ)``: plastic dilation ratio."""
        s = math.sin(math.radians(self.psi))
        return (1 + s) / (1 - s)

    @property
    def shear_fracture_energy(self) -> float:
        """Mode-II fracture energy of the bonds (N/m): ``GII``, or
        ``GII_PER_GF × Gf`` when not given."""
        return self.GII if self.GII is not None else GII_PER_GF * self.Gf

    @property
    def softening_kink(self) -> tuple[float, float] | None:
        """The kink ``(s_k, F_k)`` of a bilinear softening curve, ``None``
        for linear softening."""
        if self.softening == "linear":
            return None
        if self.softening == "bilinear":
            return PETERSSON_KINK
        return self.softening  # type: ignore[return-value]

    @property
    def critical_opening(self) -> float:
        """Crack opening ``w_c`` (m) at which the traction reaches zero:
        ``2 Gf / ft`` for linear softening, ``3.6 Gf / ft`` for Petersson's."""
        kink = self.softening_kink
        area = 0.5 if kink is None else 0.5 * (kink[0] + kink[1])
        return self.Gf / (self.ft * area)

    @property
    def snap_back_size(self) -> float:
        """Largest element size without snap-back (m): ``E' w_c / (ft
        max|s'|)``, ``2 E' Gf / ft²`` for linear softening."""
        kink = self.softening_kink
        if kink is None:
            return 2 * self.plane_strain_modulus * self.Gf / self.ft**2
        steepest = max((1 - kink[0]) / kink[1], kink[0] / (1 - kink[1]))
        return self.plane_strain_modulus * self.critical_opening / (self.ft * steepest)

    def _kernel_dict(self) -> dict[str, Any]:
        return {
            **super()._kernel_dict(),
            "kind": "mohr_coulomb_rankine",
            "c": self.c,
            "phi": self.phi,
            "psi": self.psi,
            "ft": self.ft,
            "Gf": self.Gf,
            "GII": self.shear_fracture_energy,
            "crack_band": self.crack_band,
            "softening_kink": self.softening_kink,
        }
