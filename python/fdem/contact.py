"""Interface laws for contact between free surfaces (joints, cracks, free
boundaries): node-to-segment penalty contact with Coulomb friction, cohesion
and a compression-only dashpot (paper section 2.1 and appendix D).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ._checks import number
from .errors import warn_implausible

__all__ = ["Interface"]


@dataclass(frozen=True)
class Interface:
    """The contact law of one kind of interface.

    Parameters
    ----------
    friction : float
        Friction angle φ_j (degrees), ``0 <= friction < 90``; μ = tan φ_j.
    cohesion : float
        Cohesion c_j (Pa), ``>= 0``. The interface resists slip with c_j per
        unit length of contact on top of friction, whichever side's nodes
        touch the other's facets: a node carries c_j times its tributary
        length (half of each adjacent facet) where only its side presses,
        half of that where the other side's nodes press back on it.
    damping : float
        Damping ratio ξ of the normal dashpot ``ξ · 2√(α_n μ)`` (0.5 in the
        paper; μ the reduced mass of the node and the facet), ``>= 0``. It
        acts only in compression (no sticking pull).
    normal_stiffness : float, optional
        k_n (Pa/m): contact pressure per unit penetration, the joint normal
        stiffness. A node's penalty spring is ``α_n = k_n ℓ`` with ℓ its
        tributary length on the contact (eq. 2.7 with consistent nodal
        loads). Default ``penalty_factor × E / h`` with E of the stiffest
        material and h the mean boundary-facet length of the mesh.
    shear_stiffness : float, optional
        k_s (Pa/m), the stiffness of the elastic tangential gap. Default k_n.
    penalty_factor : float
        p in the default ``k_n = p E / h`` (default 1).

    Notes
    -----
    Why ``k_n = p E / h``: an interface under a normal stress σ closes by
    σ / k_n = σ h / (p E), a fraction σ / (p E) of the element size whatever
    the mesh size. With p = 1, 20 MPa in a 60 GPa rock closes an interface
    by 0.03% of an element: a small, steady overlap, and a contact frequency
    that costs the stable step a factor of about 2 (DESIGN §4.2). Stiffer
    penalties shorten the step further and make resting contacts ring; the
    dashpot damps that.
    """

    friction: float = 30.0
    cohesion: float = 0.0
    damping: float = 0.5
    normal_stiffness: float | None = None
    shear_stiffness: float | None = None
    penalty_factor: float = 1.0

    def __post_init__(self) -> None:
        for name in ("friction", "cohesion", "damping", "penalty_factor"):
            object.__setattr__(self, name, number(name, getattr(self, name)))
        if not 0 <= self.friction < 90:
            raise ValueError(f"friction = {self.friction} must lie in [0, 90) degrees (interface friction angle)")
        if 0 < self.friction < 1:
            warn_implausible(
                f"friction = {self.friction:g} degrees: the friction angle is in degrees (a friction "
                f"coefficient of {self.friction:g} is {math.degrees(math.atan(self.friction)):.1f} degrees)"
            )
        if self.cohesion < 0:
            raise ValueError(f"cohesion = {self.cohesion} must be >= 0 (interface cohesion, Pa)")
        if self.damping < 0:
            raise ValueError(f"damping = {self.damping} must be >= 0 (contact damping ratio)")
        if self.penalty_factor <= 0:
            raise ValueError(f"penalty_factor = {self.penalty_factor} must be positive")
        for name in ("normal_stiffness", "shear_stiffness"):
            value = getattr(self, name)
            if value is not None:
                v = number(name, value)
                if v <= 0:
                    raise ValueError(f"{name} = {v} must be positive (Pa/m)")
                object.__setattr__(self, name, v)

    @property
    def mu(self) -> float:
        """Friction coefficient tan φ_j."""
        return math.tan(math.radians(self.friction))

    def _kernel_row(self, young: float, size: float) -> list[float]:
        k_n = self.normal_stiffness if self.normal_stiffness is not None else self.penalty_factor * young / size
        k_s = self.shear_stiffness if self.shear_stiffness is not None else k_n
        return [k_n, k_s, self.mu, self.cohesion, self.damping]
