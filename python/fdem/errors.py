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
    """

    def __init__(self, message: str, step: int, time: float) -> None:
        super().__init__(message)
        self.step = int(step)
        self.time = float(time)


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
