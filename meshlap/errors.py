"""The exceptions every stage raises: below every other module, so all can import them."""

import os
import sys

__all__ = ["EigenError", "MeshError", "MeshWarning", "OperatorTooLargeError", "first_line", "user_stacklevel"]


class MeshError(ValueError):
    """A mesh, parameter or function that meshlap cannot use, with the reason."""


class MeshWarning(UserWarning):
    """A mesh that meshlap can use, but whose result the caller should know more about."""


class OperatorTooLargeError(MemoryError):
    """The assembled matrix would not fit in the memory the caller allows."""


class EigenError(RuntimeError):
    """No eigensolver could verify the eigenpairs asked for (:func:`meshlap.spectral.eigs`).

    Carries the best partial result so that nothing is lost: ``eigenvalues`` (k,),
    ``vectors`` (n, k) on the vertices with mass, ``residuals`` (‖-Sφ - λMφ‖ in the M⁻¹ norm,
    per pair), ``bounds`` (each eigenvalue's error bound over ``tol`` times its scale: a pair
    passed where ≤ 1), ``count`` (eigenvalues of the pencil below ``shift`` by Sylvester's
    inertia, or None where none was counted), ``shift`` and ``tried`` (the methods run, in order).
    """

    def __init__(self, message: str, *, eigenvalues=None, vectors=None, residuals=None, bounds=None,
                 count: int | None = None, shift: float | None = None, tried: tuple = ()) -> None:
        super().__init__(message)
        self.eigenvalues, self.vectors, self.residuals, self.bounds = eigenvalues, vectors, residuals, bounds
        self.count, self.shift, self.tried = count, shift, tuple(tried)


def user_stacklevel() -> int:
    """The ``stacklevel`` that points a warning issued by the caller at the first frame outside
    meshlap: the user's line, however deep in the package the warning is made (an operator's
    pencil is built on its first use, from any of its methods).

    Examples
    --------
    >>> user_stacklevel() >= 1
    True
    """
    here = os.path.dirname(os.path.abspath(__file__))
    frame, level = sys._getframe(1), 1
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(here + os.sep):
        frame, level = frame.f_back, level + 1
    return level


def first_line(exc: BaseException) -> str:
    """The first line of an exception's message, or its type where it has none: a reader's reason,
    quoted in the :class:`MeshError` that names the file.

    Examples
    --------
    >>> first_line(ValueError("bad header\\nmore")), first_line(KeyError())
    ('bad header', 'KeyError')
    """
    return str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
