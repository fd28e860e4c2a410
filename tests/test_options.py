"""ident.IdentOptions (34-options.md): one frozen record of the data-independent settings, checked once,
passed whole by ident, choose_lag, misfit_vs_lag, Job, the DAISY runner and the command line.
(Its bad input, field by field, is in test_bad_input.py.)"""
from __future__ import annotations

import dataclasses
import inspect
import pickle

import numpy as np
import pytest

from ident import IdentOptions, Job, choose_lag, ident, misfit_vs_lag, multistart, run_jobs
from ident import daisy_runner
from ident.batch import IDENT_OPTIONS
from ident.options import IDENT_KEYWORDS
from ident.representations import random_system, simulate
from ident.solver import Settings, SLRAWarning


@pytest.fixture(scope="module")
def noisy_data() -> np.ndarray:
    rng = np.random.default_rng(28)
    system = random_system(1, 1, 2, rng)
    u = rng.standard_normal((200, 1))
    w = np.hstack([u, simulate(system, u)])
    return w + 0.05 * rng.standard_normal(w.shape)


def assert_same_identification(first, second) -> None:
    """Two results of ident equal to rounding: the misfit relative to its size, the kernel relative to its largest entry."""
    (_, info_a, wh_a, xini_a), (_, info_b, wh_b, xini_b) = first, second
    assert info_a.M == pytest.approx(info_b.M, rel=1e-10)
    assert info_a.start == info_b.start and info_a.iter == info_b.iter
    np.testing.assert_allclose(info_a.Rh, info_b.Rh, rtol=0, atol=1e-9 * np.abs(info_b.Rh).max())
    np.testing.assert_allclose(wh_a, wh_b, rtol=0, atol=1e-9 * np.abs(wh_b).max())
    np.testing.assert_allclose(xini_a, xini_b, rtol=0, atol=1e-9 * max(np.abs(xini_b).max(), 1.0))


def test_the_record_is_frozen_and_keeps_no_list_of_the_caller() -> None:
    exact, starts = [0], ["arx", "lra"]
    record = IdentOptions(exct=exact, init=starts, maxiter=np.int64(20), tol=1e-7)
    with pytest.raises(dataclasses.FrozenInstanceError):
        record.tol = 1e-3
    exact.append(1)
    starts.clear()
    assert record.exct == (0,) and record.init == ("arx", "lra")  # kept as tuples, not the caller's lists
    assert type(record.maxiter) is int and record.maxiter == 20
    wini = np.zeros((2, 2))
    assert IdentOptions(wini=wini).wini is wini  # an array is kept as given, never copied or changed


def test_ident_with_a_record_equals_ident_with_the_keywords(noisy_data) -> None:
    keywords = {"exct": [0], "init": ("arx", "lra"), "maxiter": 40, "tol": 1e-7, "refine": 1e-10, "dt": 0.5}
    by_keywords = ident(noisy_data, 1, 2, **keywords)
    record = IdentOptions(**keywords)
    by_record = ident(noisy_data, 1, 2, options=record)
    assert_same_identification(by_record, by_keywords)
    assert by_record[0].dt == 0.5
    # a keyword equal to the record's value, or at its default, is no conflict; one the record leaves at its
    # default fills it in
    assert_same_identification(ident(noisy_data, 1, 2, tol=1e-7, exct=[0], maxiter=100, options=record), by_keywords)
    partial = IdentOptions(**{**keywords, "exct": None})
    assert_same_identification(ident(noisy_data, 1, 2, exct=[0], options=partial), by_keywords)
    assert IdentOptions.merged(partial, exct=[0]) == record and IdentOptions.merged(record, exct=[0]) is record


def test_the_record_reaches_every_start_whole(noisy_data, monkeypatch) -> None:
    """The multi-start policy's tasks carry the caller's record itself, and slra gets the solver's settings."""
    tasks, settings = [], []
    run_start, slra = multistart.run_start, multistart.slra

    def recording_start(start, task):
        tasks.append(task)
        return run_start(start, task)

    def recording_slra(*args, **options):
        settings.append(options["settings"])
        return slra(*args, **options)

    monkeypatch.setattr(multistart, "run_start", recording_start)
    monkeypatch.setattr(multistart, "slra", recording_slra)
    record = IdentOptions(init=("lra", "arx"), solver={"secant": False, "max_coordinate": 5.0})
    ident(noisy_data, 1, 2, options=record)
    assert len(tasks) == 2 and all(task.options is record for task in tasks)
    assert settings and all(s is record.solver for s in settings)
    assert record.solver == dataclasses.replace(Settings(), secant=False, max_coordinate=5.0)


def test_the_solver_settings_change_the_solver(noisy_data) -> None:
    """Settings reached from ident act: two iterations that start with a damping 1e4 (the default 1e-6)
    take short steps and stop at a misfit well above the default's; a Settings and a mapping are one record."""
    as_mapping = IdentOptions(init="lra", maxiter=2, solver={"initial_damping": 1e4})
    assert as_mapping == IdentOptions(init="lra", maxiter=2, solver=Settings(initial_damping=1e4))
    with pytest.warns(SLRAWarning):
        _, default, _, _ = ident(noisy_data, 1, 2, init="lra", maxiter=2)
    with pytest.warns(SLRAWarning):
        _, damped, _, _ = ident(noisy_data, 1, 2, options=as_mapping)
    assert damped.iter == default.iter == 2
    assert damped.M > 1.2 * default.M  # measured 0.645 against 0.464 on these data


def test_ident_keywords_come_from_the_record_and_match_idents_signature() -> None:
    signature = inspect.signature(ident).parameters
    keyword_only = {name for name, p in signature.items() if p.kind is inspect.Parameter.KEYWORD_ONLY}
    assert set(IDENT_KEYWORDS) == keyword_only and len(IDENT_KEYWORDS) == len(keyword_only)
    assert IDENT_OPTIONS == IDENT_KEYWORDS
    for field in dataclasses.fields(IdentOptions):  # the record's defaults are ident's
        if field.name != "solver":
            assert signature[field.name].default == field.default, field.name


def test_a_job_takes_a_record_and_runs_as_ident(noisy_data) -> None:
    record = IdentOptions(exct=[0], init="arx", tol=1e-8)
    job = Job(noisy_data, 1, 2, record, label="record")
    assert job.options == {"options": record}
    copy = pickle.loads(pickle.dumps(job))
    assert copy.options["options"] == record
    (result,) = run_jobs([Job(noisy_data, 1, 2, {"options": record, "offset": False})])
    assert result.ok, result.error
    direct = ident(noisy_data, 1, 2, exct=[0], init="arx", tol=1e-8)
    assert_same_identification(result.outputs, direct)


def test_the_lag_functions_pass_the_record_whole(noisy_data) -> None:
    keywords = {"exct": [0], "init": "arx", "maxiter": 30, "tol": 1e-7}
    by_keywords = misfit_vs_lag(noisy_data, 1, [1, 2], **keywords)
    by_record = misfit_vs_lag(noisy_data, 1, [1, 2], options=IdentOptions(**keywords))
    np.testing.assert_allclose(by_record.misfit, by_keywords.misfit, rtol=1e-10)
    choice_keywords = choose_lag(noisy_data, 1, [1, 2, 3], **keywords)
    choice_record = choose_lag(noisy_data, 1, [1, 2, 3], options=IdentOptions(**keywords))
    assert choice_record.ell == choice_keywords.ell
    np.testing.assert_allclose(choice_record.holdout_fits, choice_keywords.holdout_fits, rtol=1e-8, atol=1e-8)


def test_the_daisy_runner_builds_one_record() -> None:
    record = daisy_runner.benchmark_options("lra", 50, 1e-6)
    assert record == IdentOptions(init="lra", maxiter=50, tol=1e-6, refine=daisy_runner.REFINE)
    assert daisy_runner.benchmark_options() == IdentOptions(maxiter=daisy_runner.SETTINGS["maxiter"],
                                                           tol=daisy_runner.SETTINGS["tol"], refine=daisy_runner.REFINE)
    with pytest.raises(ValueError, match="maxiter must satisfy 0 <= maxiter, got -1"):
        daisy_runner.run_set("dryer", maxiter=-1)  # refused before any data are read
    own = IdentOptions(init="arx", maxiter=20)
    assert daisy_runner.benchmark_options(options=own) is own  # the caller's record, whole (its refine too)


def test_the_command_line_builds_one_record(noisy_data, tmp_path, monkeypatch, capsys) -> None:
    """identify gives ident one record built from its options, and none of the record's keywords besides."""
    from ident import cli
    path = tmp_path / "data.csv"
    np.savetxt(path, noisy_data, delimiter=",", header="u,y", comments="")
    given, real = {}, cli.ident

    def recording(*args, **keywords):
        given.update(keywords)
        return real(*args, **keywords)

    monkeypatch.setattr(cli, "ident", recording)
    monkeypatch.chdir(tmp_path)  # identify writes its model file beside the working directory's name for the data
    status = cli.main(["identify", str(path), "--inputs", "u", "--outputs", "y", "--lag", "2", "--exact", "inputs", "--init", "arx",
                       "--maxiter", "50", "--tol", "1e-7", "--dt", "0.5"])
    assert status == 0, capsys.readouterr().err
    assert given["options"] == IdentOptions(exct=[0], init=("arx",), dt=0.5, maxiter=50, tol=1e-7)
    assert not set(given) & {field.name for field in dataclasses.fields(IdentOptions)}
