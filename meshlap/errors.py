"""The two exceptions every stage raises: below every other module, so all can import them."""

__all__ = ["MeshError", "MeshWarning", "OperatorTooLargeError"]


class MeshError(ValueError):
    """A mesh, parameter or function that meshlap cannot use, with the reason."""


class MeshWarning(UserWarning):
    """A mesh that meshlap can use, but whose result the caller should know more about."""


class OperatorTooLargeError(MemoryError):
    """The assembled matrix would not fit in the memory the caller allows."""
