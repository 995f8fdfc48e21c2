"""The unit registry (pint) that scene files and crash-test records are read with."""

import functools

__all__ = ["registry"]


@functools.lru_cache(maxsize=1)
def registry():
    """The one pint `UnitRegistry` of the package."""
    import pint  # deferred: importing it takes about a fifth of a second

    # pint's own disk cache of its parsed definitions (under the user's cache folder):
    # building the registry from them takes 0.02 s, from the definitions 0.2 s. Without a
    # writable cache folder, the registry is built from the definitions.
    try:
        return pint.UnitRegistry(cache_folder=":auto:")
    except OSError:
        return pint.UnitRegistry()
