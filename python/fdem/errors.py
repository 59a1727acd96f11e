"""Exceptions raised by fdem.

Bad input raises the built-in :class:`ValueError` with a message naming the
offending node, element, parameter or file line. A run that cannot continue
raises a :class:`SimulationError` subclass carrying the step, the time and the
entity concerned; output written before it stays valid.
"""

from __future__ import annotations


class SimulationError(RuntimeError):
    """A run had to stop.

    Attributes
    ----------
    step : int
        The step that failed.
    time : float
        Simulated time at the end of that step (s).
    checkpoint : str or None
        When the error stopped :meth:`fdem.Simulation.run`: the checkpoint of
        the last good state (the step before), if the run writes checkpoints.
    frame : str or None
        Likewise, the VTU frame of the last good state, if the run writes
        output.
    """

    def __init__(self, message: str, step: int, time: float) -> None:
        super().__init__(message)
        self.step = int(step)
        self.time = float(time)
        self.checkpoint: str | None = None
        self.frame: str | None = None


class InvertedElementError(SimulationError):
    """An element's area became zero or negative.

    Attributes
    ----------
    element : int
        Id of the inverted element (the smallest, if several).
    """

    def __init__(self, message: str, element: int, step: int, time: float) -> None:
        super().__init__(message, step, time)
        self.element = int(element)


class NonFiniteError(SimulationError):
    """A nodal quantity became NaN or infinite.

    Attributes
    ----------
    node : int
        Id of the node (the smallest, if several).
    quantity : str
        ``"velocity"`` or ``"position"``.
    """

    def __init__(self, message: str, node: int, quantity: str, step: int, time: float) -> None:
        super().__init__(message, step, time)
        self.node = int(node)
        self.quantity = str(quantity)


class EnergyGrowthError(SimulationError):
    """The energy balance showed energy created without a source: the run
    became unstable (the watchdog of ``Simulation(energy_growth=...)``).

    Attributes
    ----------
    created : float
        Energy created, ``-residual`` (J per unit thickness).
    largest : float
        The largest term of the balance at that step (J per unit thickness).
    """

    def __init__(self, message: str, created: float, largest: float, step: int, time: float) -> None:
        super().__init__(message, step, time)
        self.created = float(created)
        self.largest = float(largest)


class EnergyBalanceError(SimulationError):
    """The energy audit of :meth:`fdem.Simulation.run` found the balance
    residual above its tolerance and the run was asked to stop
    (``stop_on_energy_error=True``).

    Attributes
    ----------
    residual : float
        The balance residual (J per unit thickness).
    largest : float
        The largest term of the balance (J per unit thickness).
    """

    def __init__(self, message: str, residual: float, largest: float, step: int, time: float) -> None:
        super().__init__(message, step, time)
        self.residual = float(residual)
        self.largest = float(largest)


class EnergyBalanceWarning(UserWarning):
    """The energy balance residual exceeded the audit's tolerance (1% of the
    largest term by default) at an output step."""


class PlausibilityWarning(UserWarning):
    """A parameter is allowed but almost certainly a slip of units (a
    modulus in MPa, a density in t/m³, an angle in radians); the message
    names the parameter and the likely mistake."""


def warn_implausible(message: str, stacklevel: int = 3) -> None:
    """Issues a :class:`PlausibilityWarning` at the caller's caller."""
    import warnings

    warnings.warn(message, PlausibilityWarning, stacklevel=stacklevel + 1)


class CheckpointError(ValueError):
    """A checkpoint could not be written or read: the file is not a
    checkpoint, is truncated or corrupted, was written by a newer fdem, or
    belongs to another model. The message says which.

    Attributes
    ----------
    source : str
        The file (or ``"checkpoint data"``) concerned.
    """

    def __init__(self, message: str, source: str = "") -> None:
        super().__init__(message)
        self.source = str(source)
