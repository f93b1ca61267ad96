"""The one in-process cache: ``MEMO``.

A model (``System``) is a value and holds no work; a Data holds a computation's workspace.
Everything else mbsynth keeps between calls in one process lives here, in named tables:
the compiled Template and evaluators of each model structure (model/data.py), the Data
behind a model's own methods, and the memoized pure functions of the lower floors
(``MEMO.function``). Each table is bounded (least recently used out first). A cached value
changes how fast an answer comes, never the answer: ``MEMO.clear()`` empties every table.
"""

import functools
import threading
from collections import OrderedDict


class Table:
    """A bounded mapping, least recently used out first, safe across threads."""

    def __init__(self, size):
        self.size, self._entries, self._lock = size, OrderedDict(), threading.Lock()

    def get(self, key, make):
        """The entry of ``key``, made by ``make()`` when there is none (outside the lock:
        two threads may both make it; the first stored is kept)."""
        with self._lock:
            found = self._entries.get(key)
            if found is not None:
                self._entries.move_to_end(key)
                return found
        made = make()
        with self._lock:
            found = self._entries.setdefault(key, made)
            while len(self._entries) > self.size:
                self._entries.popitem(last=False)
        return found

    def last(self):
        """(key, value) of the entry used last, or None."""
        with self._lock:
            return next(reversed(self._entries.items()), None)

    def clear(self):
        with self._lock:
            self._entries.clear()

    def __len__(self):
        return len(self._entries)


class Memo:
    """The named tables and memoized functions of this process."""

    def __init__(self):
        self._tables, self._functions = {}, {}

    def table(self, name, size):
        """The table ``name`` (made on first use, ``size`` entries at most)."""
        return self._tables.setdefault(name, Table(size))

    def function(self, size):
        """A decorator: ``functools.lru_cache(size)`` on a pure function, registered here by
        its qualified name (``clear`` empties it)."""
        def decorate(f):
            cached = functools.lru_cache(maxsize=size)(f)
            self._functions[f"{f.__module__}.{f.__qualname__}"] = cached
            return cached
        return decorate

    def clear(self):
        """Empty every table and memoized function."""
        for table in self._tables.values():
            table.clear()
        for f in self._functions.values():
            f.cache_clear()

    def sizes(self):
        """{name: entries} of every table and memoized function."""
        return {**{name: len(t) for name, t in self._tables.items()},
                **{name: f.cache_info().currsize for name, f in self._functions.items()}}


MEMO = Memo()
