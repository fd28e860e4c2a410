"""ident's multi-start policy (ident.multistart) and the table of named starts (ident.starts.STARTS), issue 28:
the start's task is a named record, the table is the one place that names a start and says how it runs,
and ident, the command line and the docstrings read it."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ident import IdentOptions, cli, ident, multistart, starts
from ident.representations import random_system, simulate


@pytest.fixture(scope="module")
def noisy_data() -> np.ndarray:
    rng = np.random.default_rng(11)
    system = random_system(1, 1, 2, rng)
    u = rng.standard_normal((300, 1))
    w = np.hstack([u, simulate(system, u)])
    return w + 0.05 * rng.standard_normal(w.shape)


def test_the_start_task_is_a_frozen_record() -> None:
    fields = [field.name for field in dataclasses.fields(multistart.StartTask)]
    assert fields[:7] == ["problem", "rank", "m", "ell", "exact", "exponent", "options"]
    task = multistart.StartTask(None, 3, 1, 1, (), 0, IdentOptions())
    with pytest.raises(dataclasses.FrozenInstanceError):
        task.rank = 4


def test_each_start_is_run_as_its_row_says(noisy_data, monkeypatch) -> None:
    """The solver's own default (fallbacks=True) gets no R0, so its fall-backs come with it; the other
    starts get their kernel."""
    given, solver = {}, multistart.slra

    def recording(p, structure, rank, *, R0=None, **options):
        given.setdefault(len(given), R0)
        return solver(p, structure, rank, R0=R0, **options)

    monkeypatch.setattr(multistart, "slra", recording)
    _, info, _, _ = ident(noisy_data, 1, 2)
    assert [c.start for c in info.candidates] == list(starts.AUTO_STARTS)
    for k, name in enumerate(starts.AUTO_STARTS):
        assert (given[k] is None) == starts.STARTS[name].fallbacks, name


def test_a_start_outside_the_automatic_set_is_run_by_name_only(noisy_data, monkeypatch, tmp_path, capsys) -> None:
    """A row added to the table is a start of ident and of --init, and "auto" leaves it out."""
    row = starts.NamedStart(starts.least_squares, "least squares again (test)", automatic=False)
    monkeypatch.setitem(starts.STARTS, "lsq-test", row)
    _, info, _, _ = ident(noisy_data, 1, 2, init="lsq-test")
    _, arx, _, _ = ident(noisy_data, 1, 2, init="arx")
    assert info.start == "lsq-test" and [c.start for c in info.candidates] == ["lsq-test"]
    assert info.M == pytest.approx(arx.M, rel=1e-9)  # the same kernel, so the same minimum
    _, auto, _, _ = ident(noisy_data, 1, 2)
    assert "lsq-test" not in [c.start for c in auto.candidates]
    path = tmp_path / "data.csv"
    np.savetxt(path, noisy_data, delimiter=",", header="u,y", comments="")
    args = cli.build_parser().parse_args(["identify", str(path), "--inputs", "1", "--lag", "2", "--init", "lsq-test"])
    assert args.init == ["lsq-test"]
    with pytest.raises(ValueError, match=r"init: unknown start 'nonesuch'; expected 'auto' or one or more of "
                                         r"'lra', 'arx', 'subspace', 'lsq-test'"):
        ident(noisy_data, 1, 2, init="nonesuch")


def test_the_docstring_and_the_help_name_every_start_of_the_table() -> None:
    for name, row in starts.STARTS.items():
        assert f"{name!r} ({row.about})" in ident.__doc__
    assert "<start names>" not in ident.__doc__ and "<automatic starts>" not in ident.__doc__
    parser = cli.build_parser()
    for command in ("identify", "daisy"):
        action = next(a for a in parser.commands.choices[command]._actions if a.dest == "init")
        assert action.choices == ["auto", *starts.STARTS], command


def test_run_start_takes_a_start_to_the_candidate_ident_reports(noisy_data) -> None:
    from ident.problem import identification_problem, identification_rank, scale_exponent, scaled
    _, info, _, _ = ident(noisy_data, 1, 2, init="arx")
    exponent = scale_exponent([noisy_data])
    problem = identification_problem(scaled([noisy_data], -exponent), 2, (), [None])
    task = multistart.StartTask(problem, identification_rank([noisy_data], [None], 1, 2), 1, 2, (), exponent,
                                IdentOptions(maxiter=100, tol=1e-5))
    attempt = multistart.run_start("arx", task)
    assert attempt.candidate.start == "arx" and not attempt.candidate.error
    assert attempt.candidate.misfit == pytest.approx(info.M, rel=1e-12)
    assert np.allclose(attempt.candidate.Rh, info.Rh, rtol=1e-9, atol=1e-9 * np.abs(info.Rh).max())
