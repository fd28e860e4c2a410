"""ident.batch: many identifications through an executor, the same results wherever they run.

The Dask tests need ``distributed`` (in the ``test`` extra) and skip without it. Each starts a local
cluster of two worker processes (one, in the test of a job that cannot be pickled): a few seconds,
kept to four clusters in the module.
"""
from __future__ import annotations

import concurrent.futures
import contextlib
import dataclasses
import http.server
import multiprocessing
import os
import pickle
import signal
import socket
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import threadpoolctl

from conftest import local_http_server
from ident import Job, JobResult, SLRAWarning, dask_executor, ident, run_jobs
from ident.batch import run_job
from ident.representations import random_system, simulate


def trajectory(rng, system, n_samples, noise=0.1, x0=True):
    u = rng.standard_normal((n_samples, system.ninputs))
    x_init = rng.standard_normal(system.nstates) if x0 else None
    w0 = np.hstack([u, simulate(system, u, x_init)])
    return w0 + noise * rng.standard_normal(w0.shape)


def mixed_jobs() -> list[Job]:
    """Jobs of every kind: data forms, modes, initial conditions, starts, m = 0, and one that fails."""
    rng = np.random.default_rng(11)
    siso = random_system(1, 1, 2, rng)
    mimo = random_system(2, 2, 2, rng)
    autonomous = random_system(0, 2, 2, rng)
    w = trajectory(rng, siso, 300)
    return [
        Job(w, 1, 2, label="errors-in-variables"),
        Job(w, 1, 2, {"exct": [0]}, label="output error"),
        Job([trajectory(rng, siso, 40, x0=False), trajectory(rng, siso, 70, x0=False)], 1, 2, {"wini": 0},
            label="two series from rest"),
        Job(np.stack([trajectory(rng, siso, 60) for _ in range(3)], axis=2), 1, 2, label="T x q x N"),
        Job(w, 1, 2, {"sys0": siso, "maxiter": 50}, label="sys0 as a StateSpace"),
        Job(trajectory(rng, mimo, 3000, noise=0.2), 2, 2, {"tol": 1e-7}, label="2 x 2, T = 3000"),
        Job(trajectory(rng, autonomous, 200), 0, 2, label="m = 0"),
        Job(w[:4], 1, 2, label="too short"),
    ]


def assert_identical(first: JobResult, second: JobResult) -> None:
    """Bit for bit the same outputs (times and the worker aside), with a message that names the job."""
    assert first.job is second.job
    assert first.identical_to(second), (first.job.label, first.error, second.error)


@pytest.fixture(scope="module")
def jobs() -> list[Job]:
    return mixed_jobs()


@pytest.fixture(scope="module")
def serial(jobs) -> list[JobResult]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SLRAWarning)
        return run_jobs(jobs)


# --------------------------------------------------------------------------------------------
# jobs and results


def test_a_job_is_checked_when_it_is_made() -> None:
    w = np.zeros((10, 2))
    with pytest.raises(ValueError, match="m must satisfy 0 <= m"):
        Job(w, -1, 2)
    with pytest.raises(TypeError, match="ell must be an integer"):
        Job(w, 1, 1.5)
    with pytest.raises(TypeError, match=r"options holds exact, which ident does not take; .*exct"):
        Job(w, 1, 2, {"exact": [0]})
    with pytest.raises(TypeError, match="options must be a mapping"):
        Job(w, 1, 2, [("exct", [0])])
    options = {"exct": [0]}
    job = Job(w, np.int64(1), 2, options, label={"any": "label"})
    options["maxiter"] = 3  # the job keeps its own copy
    assert job.options == {"exct": [0]} and type(job.m) is int
    with pytest.raises(AttributeError):
        job.ell = 3  # frozen


def test_serial_results_come_in_order_with_the_failure_reported(jobs, serial) -> None:
    assert [r.job for r in serial] == jobs
    assert [r.ok for r in serial] == [True] * 7 + [False]
    failed = serial[-1]
    assert failed.error.startswith("ValueError: w is too short for the model class m = 1, ell = 2")
    assert "Traceback" in failed.traceback and "identification_rank" in failed.traceback
    assert failed.sysh is None and failed.info is None
    with pytest.raises(RuntimeError, match="job 'too short' failed: ValueError"):
        failed.outputs
    assert all(r.seconds > 0 and r.worker.endswith(f":{os.getpid()}") for r in serial)
    sysh, info, wh, xini = serial[2].outputs
    assert isinstance(wh, list) and [len(x) for x in wh] == [40, 70] and xini.shape == (2, 2)
    assert serial[3].wh.shape == (60, 2, 3) and serial[6].sysh.ninputs == 0


def test_a_job_gives_what_ident_gives(jobs, serial) -> None:
    """run_job is ident on one BLAS thread; the same bits as calling ident so."""
    for job, result in zip(jobs[:3], serial[:3]):
        with threadpoolctl.threadpool_limits(limits=1):
            sysh, info, wh, xini = ident(job.w, job.m, job.ell, **job.options)
        assert info.M == result.info.M and np.array_equal(info.Rh, result.info.Rh)
        assert np.array_equal(sysh.A, result.sysh.A) and np.array_equal(xini, result.xini)


def test_jobs_and_results_pickle_with_their_models(jobs, serial) -> None:
    job = pickle.loads(pickle.dumps(jobs[4]))  # sys0 is a StateSpace, which pickle cannot carry itself
    assert np.array_equal(job.options["sys0"].A, jobs[4].options["sys0"].A) and job.options["maxiter"] == 50
    for result in serial:
        again = pickle.loads(pickle.dumps(result))
        assert again.job.label == result.job.label
        again = JobResult(**{**again.__dict__, "job": result.job})
        assert_identical(result, again)


def test_identical_to_sees_one_bit(serial) -> None:
    result = serial[0]
    assert result.identical_to(result) and not result.identical_to(serial[1]) and not result.identical_to(serial[-1])
    assert serial[-1].identical_to(serial[-1])
    nudged = result.wh.copy()
    nudged[7, 1] = np.nextafter(nudged[7, 1], np.inf)
    assert not result.identical_to(dataclasses.replace(result, wh=nudged))
    info = dataclasses.replace(result.info, time=result.info.time + 1)  # times aside
    assert result.identical_to(dataclasses.replace(result, info=info, seconds=0.0, cpu_seconds=0.0, worker="elsewhere:1"))
    rh = result.info.Rh.copy()
    rh[0, 0] = -rh[0, 0]
    assert not result.identical_to(dataclasses.replace(result, info=dataclasses.replace(result.info, Rh=rh)))
    with pytest.raises(TypeError, match="other must be a JobResult"):
        result.identical_to(result.outputs)


def not_deprecations(recorded: tuple) -> tuple:
    """A job's recorded warnings less deprecation warnings: a job records every warning, and a newer numpy
    warns about python-control's code (the recorded pairs keep no module to tell a dependency's from
    ours; ident has no deprecations of its own, and its other warnings are kept)."""
    return tuple(w for w in recorded if not issubclass(w[0], (DeprecationWarning, PendingDeprecationWarning)))


def test_warnings_of_a_job_point_at_the_caller() -> None:
    rng = np.random.default_rng(5)
    w = trajectory(rng, random_system(1, 1, 2, rng), 200, noise=0.3)
    with pytest.warns(SLRAWarning, match=r"job 1 \(label 'stopped'\): .*maximum number of iterations") as caught:
        results = run_jobs([Job(w, 1, 2, label="fine"), Job(w, 1, 2, {"maxiter": 1, "tol": 1e-12}, label="stopped")])
    assert [w.filename for w in caught if issubclass(w.category, SLRAWarning)] == [__file__]
    assert not_deprecations(results[0].warnings) == () and not_deprecations(results[1].warnings)[0][0] is SLRAWarning
    assert not results[1].info.converged


# --------------------------------------------------------------------------------------------
# bad input


def test_an_executor_that_is_not_one_is_named() -> None:
    job = Job(np.zeros((10, 2)), 1, 1)
    for executor, message in [(3, "executor must be None .* got int, which has no submit method"),
                              ("dask", "got str"),
                              (concurrent.futures.ProcessPoolExecutor,
                               "executor must be an executor object, got the class ProcessPoolExecutor")]:
        with pytest.raises(TypeError, match=message):
            run_jobs([job], executor)


def test_a_thread_pool_is_refused_and_jobs_sharing_a_process_are_flagged() -> None:
    job = Job(np.zeros((10, 2)), 1, 1)
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        with pytest.raises(TypeError, match="executor must run the jobs in processes, not in threads"):
            run_jobs([job], pool)
        rng = np.random.default_rng(3)
        system = random_system(2, 2, 3, rng)
        jobs = [Job(trajectory(rng, system, 40_000), 2, 3) for _ in range(2)]  # a few tenths of a second each
        together = list(pool.map(run_job, jobs))  # run_job itself, in two threads at once
    for result in together:
        assert result.ok and result.warnings[-1][0] is RuntimeWarning
        assert "ran at the same time as other jobs in threads of process" in result.warnings[-1][1]
    assert not_deprecations(run_job(jobs[0]).warnings) == ()


def test_jobs_that_are_not_jobs_are_named() -> None:
    job = Job(np.zeros((10, 2)), 1, 1)
    with pytest.raises(TypeError, match=r"got a single Job; pass \[job\]"):
        run_jobs(job)
    with pytest.raises(TypeError, match=r"jobs\[1\] is a tuple"):
        run_jobs([job, (np.zeros((10, 2)), 1, 1)])
    with pytest.raises(TypeError, match=r"jobs\[0\] is a str \(2 of the 2 items"):
        run_jobs(["ab", "cd"])
    with pytest.raises(TypeError, match="jobs must be a sequence of Job, got int"):
        run_jobs(5)
    with pytest.raises(TypeError, match="job must be a Job"):
        run_job("job")
    assert run_jobs([]) == [] and run_jobs(iter([job]))[0].job is job


def test_what_the_executor_raises_is_that_jobs_error() -> None:
    """An executor that cannot run a job (here: it fails every second one) does not stop the others."""

    class Flaky:
        def __init__(self):
            self.count = 0

        def submit(self, function, *args):
            future = concurrent.futures.Future()
            self.count += 1
            if self.count % 2 == 0:
                future.set_exception(OSError("the worker is gone"))
            else:
                future.set_result(function(*args))
            return future

    rng = np.random.default_rng(1)
    w = trajectory(rng, random_system(1, 1, 1, rng), 100)
    results = run_jobs([Job(w, 1, 1, label=k) for k in range(4)], Flaky())
    assert [r.ok for r in results] == [True, False, True, False]
    assert results[1].error == "OSError (raised by the executor): the worker is gone"
    assert results[1].job.label == 1 and "OSError" in results[1].traceback


def test_jobs_are_submitted_largest_first_and_returned_in_order() -> None:
    class Recording:
        def __init__(self):
            self.order = []

        def submit(self, function, job):
            self.order.append(job.label)
            future = concurrent.futures.Future()
            future.set_result(function(job))
            return future

    rng = np.random.default_rng(2)
    system = random_system(1, 1, 1, rng)
    sizes = [50, 200, 80, 200, 120]
    jobs = [Job(trajectory(rng, system, n), 1, 1, label=k) for k, n in enumerate(sizes)]
    jobs.append(Job([trajectory(rng, system, 100), trajectory(rng, system, 60)], 1, 1, label=5))
    executor = Recording()
    results = run_jobs(jobs, executor)
    assert executor.order == [1, 3, 5, 4, 2, 0]  # 200, 200 (ties in order), 160, 120, 80, 50 samples
    assert [r.job.label for r in results] == list(range(6)) and all(r.ok for r in results)


def test_dask_executor_arguments_are_checked() -> None:
    for kwargs, error, message in [
        ({"workers": 0}, ValueError, r"workers must satisfy 1 <= workers <= \d+ \(the number of worker processes of a local cluster.*got 0"),
        ({"workers": -2}, ValueError, "got -2"),
        ({"workers": 1.5}, TypeError, "workers must be an integer"),
        ({}, ValueError, "give either workers=N .* got neither"),
        ({"workers": 2, "scheduler": "tcp://localhost:8786"}, ValueError, "not both"),
        ({"scheduler": ""}, TypeError, "scheduler must be the address"),
        ({"workers": 1, "timeout": 0}, ValueError, "timeout must be a positive number"),
    ]:
        with pytest.raises(error, match=message):
            with dask_executor(**kwargs):
                pass


def test_without_dask_the_error_says_what_to_install(monkeypatch) -> None:
    """The hint works from a clone too (issue 31): `pip install 'ident[distributed]'` would fetch the
    package index's `ident`, another project."""
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed now raises ImportError
    with pytest.raises(ImportError) as raised:
        with dask_executor(workers=1):
            pass
    message = str(raised.value)
    assert "pip install 'dask[distributed]>=2024.1'" in message
    assert "in a clone of ident's repository, pip install -e '.[distributed]'" in message
    assert "'ident[distributed]'" not in message


def test_the_dask_hint_installs_what_the_extra_installs() -> None:
    tomllib = pytest.importorskip("tomllib")  # Python 3.11 on
    from ident import batch

    project = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text(encoding="utf-8"))
    assert project["project"]["optional-dependencies"]["distributed"] == [batch.DASK_REQUIREMENT]


def test_an_unreachable_scheduler_is_a_connection_error_naming_it() -> None:
    pytest.importorskip("distributed")
    started = time.perf_counter()
    with pytest.raises(ConnectionError, match=r"cannot reach the Dask scheduler at 'tcp://127.0.0.1:9' within 1 s"):
        with dask_executor(scheduler="tcp://127.0.0.1:9", timeout=1):
            pass
    assert time.perf_counter() - started < 30
    with pytest.raises(ValueError, match="scheduler 'no port here' is not the address of a Dask scheduler"):
        with dask_executor(scheduler="no port here", timeout=1):
            pass


# --------------------------------------------------------------------------------------------
# the same results wherever the jobs run


def test_a_process_pool_gives_the_serial_results(jobs, serial) -> None:
    context = multiprocessing.get_context("spawn")  # fresh interpreters, as on another machine
    with concurrent.futures.ProcessPoolExecutor(max_workers=2, mp_context=context) as pool:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SLRAWarning)
            pooled = run_jobs(jobs, pool)
    assert len({r.worker for r in pooled}) >= 2 or len(jobs) < 2  # the jobs really ran elsewhere
    assert all(not r.worker.endswith(f":{os.getpid()}") for r in pooled)
    for first, second in zip(serial, pooled):
        assert_identical(first, second)


def test_a_dask_cluster_gives_the_serial_results(jobs, serial) -> None:
    pytest.importorskip("distributed")
    with dask_executor(workers=2) as executor:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SLRAWarning)
            remote = run_jobs(jobs, executor)
    assert all(not r.worker.endswith(f":{os.getpid()}") for r in remote)
    for first, second in zip(serial, remote):
        assert_identical(first, second)


def long_jobs(n_jobs: int) -> list[Job]:
    """Jobs of a few tenths of a second each (a few iterations on 80 000 samples): a worker killed
    soon after it started is in the middle of one."""
    rng = np.random.default_rng(4)
    system = random_system(2, 2, 3, rng)
    return [Job(trajectory(rng, system, 80_000, noise=0.2), 2, 3, label=k) for k in range(n_jobs)]


def test_a_worker_killed_in_the_middle_of_a_run_loses_nothing() -> None:
    distributed = pytest.importorskip("distributed")
    jobs = long_jobs(10)
    expected = run_jobs(jobs)
    killed = {}
    with dask_executor(workers=2) as executor:
        client = distributed.default_client()
        pids = client.run(os.getpid)  # worker address -> process id

        def kill_a_busy_worker():
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline and not killed:
                busy = [address for address, tasks in client.processing().items() if tasks]
                if busy:
                    time.sleep(0.2)  # into its job
                    killed["pid"], killed["tasks"] = pids[busy[0]], client.processing()[busy[0]]
                    os.kill(pids[busy[0]], signal.SIGKILL)
                time.sleep(0.05)

        killer = threading.Thread(target=kill_a_busy_worker)
        killer.start()
        results = run_jobs(jobs, executor)
        killer.join()
        assert killed.get("tasks"), "no worker was killed while it had a job"
        for _ in range(100):  # the nanny starts a new worker process in place of the killed one
            workers = client.run(os.getpid)
            if len(workers) == 2:
                break
            time.sleep(0.2)
        assert len(workers) == 2 and killed["pid"] not in workers.values()
    assert all(r.ok for r in results), [r.error for r in results]
    for first, second in zip(expected, results):
        assert_identical(first, second)


# ------------------------------------------------------------------- the sweeps on an executor
def test_choose_lag_on_a_dask_cluster_is_the_serial_choice() -> None:
    pytest.importorskip("distributed")
    from ident import choose_lag
    rng = np.random.default_rng(7)
    system = random_system(1, 1, 2, rng)
    w = trajectory(rng, system, 200, noise=0.01)
    here = choose_lag(w, 1, range(1, 4), exct=[0])
    with dask_executor(workers=2) as executor:
        there = choose_lag(w, 1, range(1, 4), exct=[0], executor=executor)
    assert there.ell == here.ell and there.lags == here.lags
    assert np.array_equal(there.misfits, here.misfits) and np.array_equal(there.holdout_fits, here.holdout_fits)


@pytest.mark.parametrize("executor", [3, concurrent.futures.ProcessPoolExecutor])
def test_the_sweeps_name_an_executor_that_is_not_one(executor) -> None:
    from ident import choose_lag
    from ident.daisy_runner import run_benchmark
    w = trajectory(np.random.default_rng(1), random_system(1, 1, 1, np.random.default_rng(1)), 60, noise=0.1)
    with pytest.raises(TypeError, match="executor must be"):
        choose_lag(w, 1, [1, 2], executor=executor)
    with pytest.raises(TypeError, match="executor must be"):
        ident(w, 1, 1, executor=executor)
    with pytest.raises(TypeError, match="executor must be"):
        run_benchmark(["erie"], executor=executor, progress=None)


def test_the_daisy_runner_on_a_dask_cluster_writes_the_serial_files(tmp_path) -> None:
    pytest.importorskip("distributed")
    from ident import daisy_report
    from ident.daisy_runner import run_benchmark
    data = Path(__file__).resolve().parents[2] / "shared" / "daisy"
    if not (data / "robot_arm.dat").is_file():
        pytest.skip(f"the DAISY files are not in {data}")
    names = ["erie", "robot_arm", "dryer"]
    serial = run_benchmark(names, directory=data, download_missing=False, progress=None)
    with dask_executor(workers=2) as executor:
        remote = run_benchmark(names, directory=data, download_missing=False, progress=None, executor=executor)
    assert [r.name for r in remote] == names and all(x.model is not None for r in remote for x in r.modes.values())
    first = daisy_report.write_results(serial, tmp_path / "serial")
    second = daisy_report.write_results(remote, tmp_path / "dask")
    for key in ("markdown", "csv", "json", "figure"):
        assert first[key].read_bytes() == second[key].read_bytes(), key


# --------------------------------------------------------------------------------------------
# issue 32, hostile inputs round three (batches and Dask): finished work is kept, nothing hangs,
# a local cluster is bounded by the machine


def small_jobs(labels) -> list[Job]:
    rng = np.random.default_rng(12)
    w = trajectory(rng, random_system(1, 1, 1, rng), 80)
    return [Job(w, 1, 1, label=label) for label in labels]


class Immediate:
    """An executor that runs each job at once in this process; `special` maps a job's label to what its
    future does instead: "pending" (never finishes), "interrupt" (Ctrl-C while it is awaited) or an
    exception that submit raises (as Dask does for a job it cannot pickle)."""

    def __init__(self, special):
        self.special, self.futures = special, {}

    def submit(self, function, job):
        what = self.special.get(job.label)
        if isinstance(what, Exception):
            raise what
        future = Interrupting() if what == "interrupt" else concurrent.futures.Future()
        if what is None:
            future.set_result(function(job))
        self.futures[job.label] = future
        return future


class Interrupting(concurrent.futures.Future):
    def result(self, timeout=None):
        signal.raise_signal(signal.SIGINT)  # Python's handler raises KeyboardInterrupt here, as on Ctrl-C
        raise AssertionError("SIGINT did not interrupt")


def test_a_job_that_cannot_be_submitted_fails_alone() -> None:
    jobs = small_jobs(range(4))
    cannot = TypeError("Could not serialize object of type Task")
    cannot.__cause__ = TypeError("cannot pickle '_thread.lock' object")
    results = run_jobs(jobs, Immediate({2: cannot}))
    assert [r.ok for r in results] == [True, True, False, True] and [r.job for r in results] == jobs
    assert results[2].error.startswith("TypeError (raised by the executor when the job was submitted): Could not "
                                       "serialize object of type Task (because TypeError: cannot pickle")


@pytest.mark.parametrize("where", ["process pool", "dask"])
def test_an_unpicklable_job_fails_alone_on_a_real_executor(where) -> None:
    jobs = small_jobs([0, 1, 2])
    jobs[1] = Job(jobs[1].w, 1, 1, label=threading.Lock())  # a label that no pickle can carry
    expected = run_jobs(jobs)
    if where == "dask":
        pytest.importorskip("distributed")
        executor = dask_executor(workers=1)
    else:
        context = multiprocessing.get_context("spawn")
        executor = concurrent.futures.ProcessPoolExecutor(max_workers=1, mp_context=context)
    with executor as running:
        results = run_jobs(jobs, running)
    assert [r.ok for r in results] == [True, False, True]
    assert "raised by the executor" in results[1].error and "pickle" in results[1].error
    for first, second in zip(expected[::2], results[::2]):
        assert_identical(first, second)


def test_ctrl_c_while_waiting_keeps_the_finished_results() -> None:
    from ident.batch import CANCELLED, JobsInterrupted
    jobs = small_jobs(range(5))  # equal sizes: submitted in order
    executor = Immediate({1: "interrupt", 3: "pending"})
    with pytest.raises(JobsInterrupted, match="3 of 5 jobs had finished") as caught:
        run_jobs(jobs, executor)
    assert isinstance(caught.value, KeyboardInterrupt)  # a program that does not catch it stops as on Ctrl-C
    results = caught.value.results
    assert [r.job for r in results] == jobs and [r.ok for r in results] == [True, False, True, False, True]
    assert results[1].error == results[3].error == CANCELLED  # 4 finished while job 1 was awaited: kept
    assert executor.futures[3].cancelled()  # the unfinished job does not go on running
    again = pickle.loads(pickle.dumps(caught.value))
    assert [r.ok for r in again.results] == [r.ok for r in results]


def test_ctrl_c_in_a_serial_run_keeps_the_finished_results(monkeypatch) -> None:
    from ident import batch
    from ident.batch import CANCELLED, JobsInterrupted
    calls = []

    def interrupted_third(*args, **options):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return ident(*args, **options)

    monkeypatch.setattr(batch, "ident", interrupted_third)
    jobs = small_jobs(range(4))
    with pytest.raises(JobsInterrupted, match="2 of 4 jobs had finished") as caught:
        run_jobs(jobs)
    assert [r.ok for r in caught.value.results] == [True, True, False, False]
    assert caught.value.results[2].error == CANCELLED and caught.value.results[0].job is jobs[0]


def test_a_local_cluster_is_bounded_by_the_machine_before_dask_is_imported(monkeypatch) -> None:
    from ident.batch import MAX_WORKERS_PER_CPU, max_local_workers
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    assert max_local_workers() == MAX_WORKERS_PER_CPU * usable
    monkeypatch.setitem(sys.modules, "distributed", None)  # nothing of Dask may be touched
    for workers in (10**6, max_local_workers() + 1):
        with pytest.raises(ValueError, match=rf"workers must satisfy 1 <= workers <= {max_local_workers()} "
                                             rf"\(the number of worker processes of a local cluster.*got {workers}"):
            with dask_executor(workers=workers):
                pass


def test_the_command_line_bounds_workers_before_any_cluster(monkeypatch, tmp_path, capsys) -> None:
    distributed = pytest.importorskip("distributed")
    from ident import cli

    def no_cluster(*args, **kwargs):
        raise AssertionError("a local cluster was started")

    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    status = cli.main(["daisy", "erie", "--workers", "1000000", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert status == 2 and "--workers: workers must satisfy 1 <= workers <=" in err and "got 1000000" in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err and not (tmp_path / "out").exists()


@contextlib.contextmanager
def not_a_scheduler(kind: str):
    """A local address that accepts TCP connections and is no Dask scheduler: a silent server, or HTTP."""
    if kind == "http":
        class Quiet(http.server.BaseHTTPRequestHandler):
            def do_GET(self):
                self.send_response(200)
                self.end_headers()
                self.wfile.write(b"<html>a dashboard</html>")

            def log_message(self, *args):
                pass

        with local_http_server(Quiet) as port:
            yield f"tcp://127.0.0.1:{port}"
        return
    listener = socket.create_server(("127.0.0.1", 0))
    listener.settimeout(0.1)
    accepted, done = [], threading.Event()

    def accept_and_stay_silent():
        while not done.is_set():
            try:
                accepted.append(listener.accept()[0])
            except OSError:  # the timeout: look at done again
                pass

    thread = threading.Thread(target=accept_and_stay_silent, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    finally:
        done.set()
        thread.join(timeout=5)
        listener.close()
        for connection in accepted:
            connection.close()


def within(seconds: float, function):
    """What function() returned or raised, from a daemon thread given `seconds`: a call that hangs fails
    the test instead of hanging it."""
    outcome = {}

    def call():
        try:
            outcome["returned"] = function()
        except BaseException as error:  # handed to the test
            outcome["raised"] = error

    thread = threading.Thread(target=call, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"still waiting after {seconds} s"
    return outcome


def enter_dask_executor(**arguments):
    with dask_executor(**arguments):
        pass


@pytest.mark.parametrize("kind", ["silent", "http"])
def test_an_address_that_is_no_scheduler_is_reported_within_the_timeout(kind) -> None:
    pytest.importorskip("distributed")
    with not_a_scheduler(kind) as address:  # Dask alone waited for minutes (for ever, in principle)
        outcome = within(30, lambda: enter_dask_executor(scheduler=address, timeout=2))
    with pytest.raises(ConnectionError, match=rf"cannot reach the Dask scheduler at '{address}' within 2 s "
                                              r".*no answer as a Dask scheduler"):
        raise outcome.get("raised") or AssertionError(f"no error: {outcome}")


def test_daisy_scheduler_that_is_no_scheduler_exits_2_within_its_timeout(monkeypatch, tmp_path, capsys) -> None:
    pytest.importorskip("distributed")
    from ident import cli
    monkeypatch.setattr(cli, "SCHEDULER_TIMEOUT", 2.0)
    with not_a_scheduler("http") as address:
        status = within(30, lambda: cli.main(["daisy", "erie", "--scheduler", address, "--out",
                                              str(tmp_path / "out")])).get("returned")
    err = capsys.readouterr().err
    assert status == 2 and f"--scheduler: cannot reach the Dask scheduler at '{address}' within 2 s" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "out").exists()


def test_a_running_scheduler_is_used_and_a_workers_address_named() -> None:
    distributed = pytest.importorskip("distributed")
    in_process = dict(n_workers=1, processes=False, threads_per_worker=1, dashboard_address=None)
    with distributed.LocalCluster(**in_process) as cluster:
        with dask_executor(scheduler=cluster.scheduler_address, timeout=10) as executor:
            assert run_jobs(small_jobs([0]), executor)[0].ok
        worker = next(iter(cluster.scheduler_info["workers"]))
        with pytest.raises(ValueError, match=rf"scheduler '{worker}' answers as a Dask Worker, not as a scheduler"):
            with dask_executor(scheduler=worker, timeout=5):
                pass


# --- issue 31 point 7 (the small edges): a local cluster logs only Dask's errors, and puts its handlers back ---

def test_a_local_cluster_logs_only_dasks_errors_while_it_lives() -> None:
    """Dask's handler of its log (on the standard error; Dask adds it where the program configured no
    logging, as the command line does, and not under pytest: here one like it) shows Dask's errors and
    not its warnings while the cluster lives, and is put back after."""
    pytest.importorskip("distributed")
    import io
    import logging

    shown = io.StringIO()
    handler = logging.StreamHandler(shown)
    dask_log, nanny_log = logging.getLogger("distributed"), logging.getLogger("distributed.nanny")
    dask_log.addHandler(handler)
    try:
        with dask_executor(workers=1) as executor:
            assert executor.submit(sum, [1, 2]).result() == 3
            nanny_log.warning("a warning of Dask's while the cluster lives")
            nanny_log.error("an error of Dask's while the cluster lives")
        nanny_log.warning("a warning of Dask's after the cluster")
    finally:
        dask_log.removeHandler(handler)
    lines = shown.getvalue().splitlines()
    assert lines == ["an error of Dask's while the cluster lives", "a warning of Dask's after the cluster"], lines
    assert handler.level == logging.NOTSET
