"""newest(): a live source's frames read as they come, the caller given the newest (the ones it
was too slow for dropped). Ordered by events, not by time."""
import threading

import pytest

from mocap.io.prefetch import newest


def test_the_caller_gets_the_newest_item_and_the_gaps_are_the_dropped_ones():
    taken, produced = threading.Event(), threading.Event()
    closed = []

    def make():
        try:
            yield "first"
            taken.wait(timeout=30)          # until the caller has the first
            for i in range(1, 6):
                yield f"item {i}"           # the caller is busy: each replaces the one before
            produced.set()
        finally:
            closed.append(True)

    items = newest(make)
    first = next(items)
    assert (first.position, first.item) == (0, "first")
    taken.set()
    assert produced.wait(timeout=30)
    last = next(items)
    assert (last.position, last.item) == (5, "item 5")          # items 1-4 dropped
    assert last.time_s >= first.time_s
    assert list(items) == []
    assert closed == [True]


def test_an_error_of_the_reader_comes_out_and_stopping_early_closes_it():
    def failing():
        yield 1
        raise OSError("camera unplugged")

    got = []
    with pytest.raises(OSError, match="unplugged"):
        for arrival in newest(failing):
            got.append(arrival.item)
    assert got in ([1], [])

    closed = threading.Event()

    def endless():
        try:
            i = 0
            while True:
                yield i
                i += 1
        finally:
            closed.set()

    items = newest(endless)
    next(items)
    items.close()                                   # the caller stops: the reader closes its iterator
    assert closed.wait(timeout=30)
