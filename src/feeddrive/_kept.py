"""What a module keeps between calls (models built, switching rows found, stability bands):
a map of the newest entries, safe for the explorer's job threads, bounded in number and,
where entries can be large, in their total size."""

from __future__ import annotations

import collections
import threading
from collections.abc import Callable, Iterator
from typing import Any


class Kept:
    """The newest ``size`` entries (the least recently read or written leave first); with
    ``weigh``, also at most ``budget`` of their weights together, an entry heavier than the
    whole budget not kept at all.  Every read and write holds one lock.

    Parameters
    ----------
    size : int
        Most entries kept.
    weigh : callable or None, default None
        An entry's weight (e.g. its arrays' bytes); None: no weight bound.
    budget : float, default inf
        Most weight kept together.
    """

    def __init__(self, size: int, weigh: Callable[[Any], float] | None = None,
                 budget: float = float("inf")) -> None:
        self.size, self.weigh, self.budget = size, weigh, budget
        self._items: collections.OrderedDict[Any, Any] = collections.OrderedDict()
        self._lock = threading.Lock()

    def get(self, key: Any) -> Any:
        """The entry of ``key``, now the newest, or None."""
        with self._lock:
            value = self._items.get(key)
            if value is not None:
                self._items.move_to_end(key)
            return value

    def put(self, key: Any, value: Any) -> None:
        """Keep ``value`` as the newest entry, the oldest leaving while a bound is passed."""
        weigh = self.weigh
        with self._lock:
            if weigh is None or weigh(value) <= self.budget:
                self._items[key] = value
                self._items.move_to_end(key)
            # the weight kept, summed once and lessened by each entry that leaves (summed
            # again on every pass, a put cost a whole sum per entry leaving)
            total = 0 if weigh is None else sum(map(weigh, self._items.values()))
            while len(self._items) > self.size or total > self.budget:
                _, left = self._items.popitem(last=False)
                if weigh is not None:
                    total -= weigh(left)

    def values(self) -> list[Any]:
        """The entries, the oldest first."""
        with self._lock:
            return list(self._items.values())

    def __contains__(self, key: Any) -> bool:
        with self._lock:
            return key in self._items

    def __iter__(self) -> Iterator[Any]:
        with self._lock:
            return iter(list(self._items))

    def __len__(self) -> int:
        with self._lock:
            return len(self._items)
