"""The reproduce runner's task queue (issue 21, sixth round): tasks are handed to the pool as
its workers free up, and a study whose input became known starts next — not after every task
submitted before it (the compensation study used to run last and alone for ≈ 4 s)."""

from __future__ import annotations

from feeddrive.reproduce.runner import TaskQueue


def _task(name: str) -> tuple[str, tuple[object, tuple[()]]]:
    return name, (print, ())


def test_the_pool_holds_at_most_its_slots() -> None:
    queue = TaskQueue([_task(k) for k in "abcde"], slots=3)
    assert [k for k, _ in queue.take(0)] == ["a", "b", "c"]
    assert queue.take(3) == []  # three in the pool: none more
    assert [k for k, _ in queue.take(2)] == ["d"]  # one finished: the next
    assert [k for k, _ in queue.take(0)] == ["e"]
    assert queue.take(0) == [] and queue.items == []


def test_a_study_whose_input_is_known_starts_next() -> None:
    queue = TaskQueue([_task(k) for k in "abcde"], slots=3)
    queue.take(0)
    queue.first("compensation", (print, ()))
    assert [k for k, _ in queue.take(2)] == ["compensation"]
    assert [k for k, _ in queue.items] == ["d", "e"]
