"""A cache of at most a given number of entries, the least recently used dropped first: the
simulator's caches of reduced networks and models, which a screening worker would otherwise
grow by every fault it runs (ACTIVSg2000: about 33 MB a fault, docs/scale.md)."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

V = TypeVar("V")


class BoundedCache(Generic[V]):
    """Values built on first use and kept for the `size` most recently used keys.

    Parameters
    ----------
    size : int
        Most entries kept (>= 1).

    Raises
    ------
    ValueError
        `size` below 1.
    """

    def __init__(self, size: int) -> None:
        if size < 1:
            raise ValueError(f"a bounded cache needs size >= 1, got {size}")
        self.size = size
        self._entries: OrderedDict[Hashable, V] = OrderedDict()

    def get(self, key: Hashable, build: Callable[[], V]) -> V:
        """The value of `key`, built by ``build()`` when absent (then the least recently
        used entry beyond `size` is dropped)."""
        if key in self._entries:
            self._entries.move_to_end(key)
            return self._entries[key]
        value = build()
        self._entries[key] = value
        if len(self._entries) > self.size:
            self._entries.popitem(last=False)
        return value

    def __len__(self) -> int:
        return len(self._entries)

    def __contains__(self, key: Hashable) -> bool:
        return key in self._entries
