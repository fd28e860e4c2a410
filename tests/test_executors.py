"""ident.executors: the one policy for parallel work (issues 28 and 30).

Largest first submitted, results in the caller's order, pending work cancelled on Ctrl-C, what the
executor cannot run reported as that task's result (or raised where the caller gives no `failed`),
and no python-control StateSpace ever pickled on the way to or from a worker: for `run_tasks` itself
and for its four callers (`run_jobs`, `ident`'s candidates, `choose_lag`, the DAISY runner).
The executors here run in this process and pickle what a process pool would, so the tests are quick
and deterministic; the real process pools and Dask clusters are in tests/test_batch.py.
"""
from __future__ import annotations

import concurrent.futures
import io
import pickle
import signal
from pathlib import Path

import numpy as np
import pytest

from ident import Job, ident, run_jobs
from ident.executors import SUBMITTED, StateSpaceMatrices, TasksInterrupted, portable, restored, run_tasks
from ident.representations import is_state_space, make_ss, random_system, simulate


def square(x: float) -> float:
    return x * x


class Recording:
    """Runs each task at once here; records the submission order; `special` maps a task's first argument
    to what happens instead: "pending" (never finishes), "interrupt" (Ctrl-C while awaited), an exception
    that submit raises, or ("future", exception) that the future holds."""

    def __init__(self, special=None):
        self.special, self.order, self.futures = special or {}, [], {}

    def submit(self, function, *args):
        what = self.special.get(args[0])
        self.order.append(args[0])
        if isinstance(what, Exception):
            raise what
        future = Interrupting() if what == "interrupt" else concurrent.futures.Future()
        if isinstance(what, tuple):
            future.set_exception(what[1])
        elif what is None:
            future.set_result(function(*args))
        self.futures[args[0]] = future
        return future


class Interrupting(concurrent.futures.Future):
    def result(self, timeout=None):
        signal.raise_signal(signal.SIGINT)  # Python's handler raises KeyboardInterrupt here, as on Ctrl-C
        raise AssertionError("SIGINT did not interrupt")


class NoStateSpace(pickle.Unpickler):
    """An unpickler that refuses any class of python-control: what a worker would have to import."""

    def find_class(self, module, name):
        if module == "control" or module.startswith("control."):
            raise AssertionError(f"{module}.{name} crossed the process boundary")
        return super().find_class(module, name)


def across(value):
    return NoStateSpace(io.BytesIO(pickle.dumps(value))).load()


class Pickling:
    """An executor that does to each task what a process pool does: the function and its arguments
    pickled on the way out, the result on the way back (here, in this process); it counts the calls."""

    def __init__(self):
        self.calls = 0

    def submit(self, function, *args):
        self.calls += 1
        function, args = across((function, args))
        future = concurrent.futures.Future()
        future.set_result(across(function(*args)))
        return future


# ----------------------------------------------------------------------------------- the policy


def test_results_come_in_the_order_of_the_tasks_and_the_largest_is_submitted_first() -> None:
    executor = Recording()
    tasks = [(x,) for x in [1.0, 2.0, 3.0, 4.0, 5.0]]
    results = run_tasks(square, tasks, executor, sizes=[10, 50, 20, 50, 30])
    assert results == [1.0, 4.0, 9.0, 16.0, 25.0]
    assert executor.order == [2.0, 4.0, 5.0, 3.0, 1.0]  # 50, 50 (ties in order), 30, 20, 10
    plain = Recording()
    run_tasks(square, tasks, plain)  # no sizes: the caller's order
    assert plain.order == [1.0, 2.0, 3.0, 4.0, 5.0]


def test_without_an_executor_the_tasks_run_here_in_order() -> None:
    seen = []
    assert run_tasks(square, [(2.0,), (3.0,)], done=lambda k, r: seen.append((k, r))) == [4.0, 9.0]
    assert seen == [(0, 4.0), (1, 9.0)]


def test_what_the_executor_cannot_run_is_that_tasks_result() -> None:
    executor = Recording({2.0: TypeError("cannot pickle"), 3.0: ("future", OSError("worker lost"))})
    results = run_tasks(square, [(1.0,), (2.0,), (3.0,), (4.0,)], executor,
                        failed=lambda error, when: f"{type(error).__name__} {when}".strip())
    assert results == [1.0, f"TypeError {SUBMITTED}", "OSError", 16.0]


def test_without_failed_the_executors_error_is_raised_and_the_rest_cancelled() -> None:
    executor = Recording({1.0: ("future", OSError("worker lost")), 3.0: "pending"})
    with pytest.raises(OSError, match="worker lost"):
        run_tasks(square, [(1.0,), (2.0,), (3.0,)], executor)
    assert executor.futures[3.0].cancelled()


def test_ctrl_c_cancels_the_pending_tasks_and_keeps_the_finished_ones() -> None:
    executor = Recording({2.0: "interrupt", 4.0: "pending"})
    with pytest.raises(TasksInterrupted, match="3 of 5 tasks finished") as caught:
        run_tasks(square, [(x,) for x in [1.0, 2.0, 3.0, 4.0, 5.0]], executor)
    assert isinstance(caught.value, KeyboardInterrupt)
    assert caught.value.finished == {0: 1.0, 2: 9.0, 4: 25.0}  # 3.0 and 5.0 finished while 2.0 was awaited
    assert executor.futures[4.0].cancelled()
    assert pickle.loads(pickle.dumps(caught.value)).finished == caught.value.finished


def test_ctrl_c_in_a_serial_run_keeps_the_finished_tasks() -> None:
    def interrupted_third(x):
        if x == 3.0:
            raise KeyboardInterrupt
        return square(x)

    with pytest.raises(TasksInterrupted) as caught:
        run_tasks(interrupted_third, [(1.0,), (2.0,), (3.0,), (4.0,)])
    assert caught.value.finished == {0: 1.0, 1: 4.0} and caught.value.total == 4


def test_a_model_travels_as_its_matrices_and_comes_back_whole() -> None:
    system = make_ss(np.array([[0.5]]), np.array([[1.0]]), np.array([[2.0]]), np.array([[0.0]]), dt=0.1,
                     inputs=["u"], outputs=["y"])
    with pytest.raises((AssertionError, AttributeError, pickle.PicklingError)):
        across(system)  # the model itself cannot cross: the unpickler here would name it, or pickle fails
    travelled = across(portable(system))
    assert isinstance(travelled, StateSpaceMatrices)
    back = restored(travelled)
    assert is_state_space(back) and back.dt == 0.1 and list(back.input_labels) == ["u"]
    assert all(np.array_equal(getattr(back, x), getattr(system, x)) for x in "ABCD")
    assert portable(3.0) == 3.0 and restored("text") == "text"


# ------------------------------------------------------------------ the callers use the policy


def data(seed: int = 5, samples: int = 120):
    rng = np.random.default_rng(seed)
    system = random_system(1, 1, 2, rng)
    u = rng.standard_normal((samples, 1))
    return system, np.hstack([u, simulate(system, u)]) + 0.02 * rng.standard_normal((samples, 2))


def test_run_jobs_sends_no_state_space_and_gets_the_serial_results() -> None:
    system, w = data()
    jobs = [Job(w, 1, 2, {"sys0": system}, label="from a model"), Job(w, 1, 2, label="plain")]
    executor = Pickling()
    remote, here = run_jobs(jobs, executor), run_jobs(jobs)
    assert executor.calls == 2 and all(r.ok for r in remote)
    for first, second in zip(here, remote):
        assert first.identical_to(second)


def test_idents_candidates_and_the_lag_sweep_send_no_state_space() -> None:
    from ident.validation import choose_lag
    _, w = data()
    executor = Pickling()
    sysh, info, _, _ = ident(w, 1, 2, init="auto", executor=executor)
    assert executor.calls == len(info.candidates) > 1
    serial_info = ident(w, 1, 2, init="auto")[1]
    assert info.M == serial_info.M and np.array_equal(info.Rh, serial_info.Rh)
    sweep = Pickling()
    there = choose_lag(w, 1, [1, 2], exct=[0], executor=sweep)
    assert sweep.calls >= 2 and there.ell == choose_lag(w, 1, [1, 2], exct=[0]).ell


def test_the_daisy_runner_sends_no_state_space_one_job_per_set_mode_and_replay() -> None:
    from ident import daisy_runner
    folder = Path(__file__).resolve().parents[2] / "shared" / "daisy"
    if not (folder / "erie.dat").is_file():
        pytest.skip(f"the DAISY files are not in {folder}")
    executor = Pickling()
    remote = daisy_runner.run_benchmark(["erie"], directory=folder, download_missing=False, modes=["oe"],
                                        progress=None, executor=executor)
    assert executor.calls == daisy_runner.REPLAYS + 1
    serial = daisy_runner.run_benchmark(["erie"], directory=folder, download_missing=False, modes=["oe"],
                                        progress=None)
    there, here = remote[0].modes["oe"], serial[0].modes["oe"]
    assert is_state_space(there.model) and all(np.array_equal(getattr(there.model, x), getattr(here.model, x))
                                               for x in "ABCD")
    assert (there.misfit, there.fit, there.account, there.start) == (here.misfit, here.fit, here.account, here.start)
