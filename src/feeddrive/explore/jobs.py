"""Background work for the page: each run is a job in its own thread, with progress the page
polls and a cancel flag the work checks at every progress report (a critical-speed search
stops after the trial it is in; a single simulation is stopped inside the compiled solver,
after the step it is in: :meth:`feeddrive.engine.simulate.Simulation.request_stop`)."""

from __future__ import annotations

import itertools
import threading
import time
import traceback
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from dataclasses import field as _field
from typing import Any

from ..parameters import ParameterError

#: jobs running at once; more are refused with a message (2 cores: more would only queue)
MAX_RUNNING = 4
#: finished jobs kept for the page to collect
KEEP = 64


class Cancelled(Exception):
    """Raised inside a job's work when the page cancelled it."""


class Busy(RuntimeError):
    """Too many jobs running."""


@dataclass
class Job:
    id: str
    kind: str
    state: str = "running"  # running, done, failed, cancelled
    done: float = 0.0
    total: float = 0.0
    text: str = ""
    started: float = _field(default_factory=time.monotonic)
    finished: float | None = None
    result: Any = None
    error: str | None = None
    field: str | None = None  # the page field its error belongs beside
    cancel_event: threading.Event = _field(default_factory=threading.Event)
    expected_s: float | None = None  # wall time the work is expected to take

    def report(self, done: float, total: float, text: str) -> None:
        """Progress from the work; raises :class:`Cancelled` once the page cancelled."""
        if self.cancel_event.is_set():
            raise Cancelled
        self.done, self.total, self.text = float(done), float(total), text

    def as_dict(self) -> dict[str, Any]:
        end = self.finished if self.finished is not None else time.monotonic()
        out: dict[str, Any] = {
            "id": self.id, "kind": self.kind, "state": self.state,
            "progress": {"done": self.done, "total": self.total, "text": self.text},
            "elapsed_s": round(end - self.started, 3), "expected_s": self.expected_s,
        }
        if self.state == "done":
            out["result"] = self.result
        if self.error is not None:
            out["error"] = self.error
            out["field"] = self.field
        return out


Work = Callable[[Job], Any]
ErrorField = Callable[[BaseException], str | None]


class Jobs:
    """The jobs of one server."""

    def __init__(self) -> None:
        self._jobs: OrderedDict[str, Job] = OrderedDict()
        self._lock = threading.Lock()
        self._ids = itertools.count(1)

    def running(self) -> int:
        with self._lock:
            return sum(j.state == "running" for j in self._jobs.values())

    def start(self, kind: str, work: Work, error_field: ErrorField | None = None,
              expected_s: float | None = None, text: str = "", total: float = 0.0) -> Job:
        """Run ``work(job)`` in a thread; ``text`` and ``total`` are its progress until it
        reports its own."""
        with self._lock:
            if sum(j.state == "running" for j in self._jobs.values()) >= MAX_RUNNING:
                raise Busy(f"{MAX_RUNNING} runs are going on; cancel one or wait")
            job = Job(id=f"{kind}-{next(self._ids)}", kind=kind, expected_s=expected_s,
                      text=text, total=total)
            self._jobs[job.id] = job
            while len(self._jobs) > KEEP:
                oldest = next(iter(self._jobs.values()))
                if oldest.state == "running":
                    break
                self._jobs.popitem(last=False)
        thread = threading.Thread(target=self._run, args=(job, work, error_field),
                                  name=f"feeddrive-explore-{job.id}", daemon=True)
        thread.start()
        return job

    @staticmethod
    def _run(job: Job, work: Work, error_field: ErrorField | None) -> None:
        try:
            result = work(job)
        except Cancelled:
            job.state = "cancelled"
        except (ParameterError, ValueError, RuntimeError) as err:
            # a refused value or a solver that gave up: a message for the page
            job.error = str(err)
            job.field = error_field(err) if error_field else None
            job.state = "failed"
        except Exception as err:  # the server must outlive any bug
            traceback.print_exc()
            job.error = f"internal error: {type(err).__name__}: {err}"
            job.state = "failed"
        else:
            job.result = result
            job.state = "cancelled" if job.cancel_event.is_set() else "done"
        finally:
            job.finished = time.monotonic()

    def get(self, job_id: str) -> Job | None:
        with self._lock:
            return self._jobs.get(job_id)

    def cancel(self, job_id: str) -> Job | None:
        job = self.get(job_id)
        if job is not None and job.state == "running":
            job.cancel_event.set()
        return job

    def wait(self, job_id: str, timeout: float) -> Job | None:
        """For tests and the CLI: block until the job ended or ``timeout`` [s] passed."""
        end = time.monotonic() + timeout
        job = self.get(job_id)
        while job is not None and job.state == "running" and time.monotonic() < end:
            time.sleep(0.01)
        return job
