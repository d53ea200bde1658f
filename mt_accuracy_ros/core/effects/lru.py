"""A least-recently-used store of arrays bounded in bytes.

The selection keeps designs and sensitivities in it, a context the columns several
candidates share, a set of readings its lagged signals: each is cheap to make again
beside the page faults of holding too much (docs/benchmarks.md).
"""
from __future__ import annotations

from collections import OrderedDict
from typing import Hashable

from numpy.typing import NDArray


class ByteBoundedCache:
    """Arrays by key, the least recently used dropped beyond ``max_bytes``.

    ``min_items``: an array too large for the store to hold this many of its size is
    handed back without being kept (a store that cannot hold what is asked for again
    before it is asked for only costs memory).

    Parameters
    ----------
    max_bytes : int
        Most bytes held [bytes].
    min_items : int, optional
        How many arrays of one size the store must hold for it to keep one.
    """

    def __init__(self, max_bytes: int, min_items: int = 1) -> None:
        self.max_bytes = int(max_bytes)
        self.min_items = int(min_items)
        self._items: OrderedDict[Hashable, NDArray] = OrderedDict()
        self.nbytes = 0

    def __contains__(self, key: Hashable) -> bool:
        return key in self._items

    def __len__(self) -> int:
        return len(self._items)

    def get(self, key: Hashable) -> NDArray | None:
        """The array under ``key``, made the most recently used, or None.

        Parameters
        ----------
        key : hashable
            The key.

        Returns
        -------
        ndarray or None
            The array kept (not a copy), or None.
        """
        item = self._items.get(key)
        if item is not None:
            self._items.move_to_end(key)
        return item

    def put(self, key: Hashable, item: NDArray) -> bool:
        """Keep ``item`` under ``key`` (True), or not when it is too large (False).

        Parameters
        ----------
        key : hashable
            The key.
        item : ndarray
            The array kept (not copied).

        Returns
        -------
        bool
            Whether it was kept; the least recently used are dropped beyond ``max_bytes``.
        """
        if self.min_items > 1 and item.nbytes * self.min_items > self.max_bytes:
            return False
        self._items[key] = item
        self.nbytes += item.nbytes
        while self.nbytes > self.max_bytes and len(self._items) > 1:
            _, dropped = self._items.popitem(last=False)
            self.nbytes -= dropped.nbytes
        return True
