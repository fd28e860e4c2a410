"""A catalogue of bad input: each case gives a ValueError/TypeError that names the argument, what was
expected and what was given, raised by ident's own checks (not from inside numpy, scipy or control)."""
from __future__ import annotations

import os
import traceback

import control
import numpy as np
import pytest

from ident import ident, misfit
from ident.representations import random_system
from ident.solver import kernel_misfit, slra
from ident.structure import Structure

RNG = np.random.default_rng(0)
W = RNG.standard_normal((60, 3))
SYS = random_system(1, 2, 1, RNG)
W_WITH_NAN = np.where(np.arange(180).reshape(60, 3) == 7, np.nan, W)
W_WITH_INF = np.where(np.arange(180).reshape(60, 3) == 7, np.inf, W)
STRUCTURE = Structure.time_major(3, 1, [59])
P = STRUCTURE.params_from_series([W])

CASES = [
    ('1-D w', lambda: ident(np.ones(50), 1, 1),
     ValueError, 'w must be a T x q array'),
    ('string w', lambda: ident("abc", 1, 1),
     TypeError, 'w must be a numpy array or a sequence'),
    ('scalar w', lambda: ident(3.0, 1, 1),
     TypeError, 'w must be a numpy array or a sequence'),
    ('list of lists', lambda: ident([[1,2],[3,4]], 1, 1),
     ValueError, 'w\\[0\\] must be a T x q array'),
    ('nested 1-D list', lambda: ident([np.ones(5)], 1, 1),
     ValueError, 'w\\[0\\] must be a T x q array'),
    ('mismatched widths', lambda: ident([np.ones((30,2)), np.ones((30,3))], 1, 1),
     ValueError, 'same number of variables q; got \\[2, 3\\]'),
    ('4-D', lambda: ident(np.ones((5,2,2,2)), 1, 1),
     ValueError, 'got an array of shape \\(5, 2, 2, 2\\)'),
    ('complex', lambda: ident(W.astype(complex), 1, 1),
     TypeError, 'w must hold real numbers, got dtype complex128'),
    ('object', lambda: ident(np.array([[1,'a']],dtype=object), 1, 1),
     TypeError, 'must hold real numbers, got dtype object'),
    ('nan', lambda: ident(W_WITH_NAN, 1, 1),
     ValueError, 'non-finite value.*first at sample 2, variable 1'),
    ('transposed', lambda: ident(W.T, 1, 1),
     ValueError, 'too short.*is it transposed'),
    ('m neg', lambda: ident(W, -1, 1),
     ValueError, 'm must satisfy 0 <= m <= 2.*got -1'),
    ('m>q', lambda: ident(W, 4, 1),
     ValueError, 'm must satisfy 0 <= m <= 2.*got 4'),
    ('m=q', lambda: ident(W, 3, 1),
     ValueError, 'm = q would leave no outputs.*got 3'),
    ('m float', lambda: ident(W, 1.0, 1),
     TypeError, 'm must be an integer, got 1.0'),
    ('ell neg', lambda: ident(W, 1, -1),
     ValueError, 'ell must satisfy 0 <= ell, got -1'),
    ('ell float', lambda: ident(W, 1, 1.5),
     TypeError, 'ell must be an integer, got 1.5'),
    ('ell str', lambda: ident(W, 1, "2"),
     TypeError, "ell must be an integer, got '2'"),
    ('exct out', lambda: ident(W, 1, 1, exct=[3]),
     ValueError, 'exct indices must lie in 0 .. q-1 = 2, got \\[3\\]'),
    ('exct neg', lambda: ident(W, 1, 1, exct=[-1]),
     ValueError, 'exct indices must lie in 0 .. q-1 = 2, got \\[-1\\]'),
    ('exct dup', lambda: ident(W, 1, 1, exct=[0,0]),
     ValueError, 'exct lists a variable more than once: \\[0, 0\\]'),
    ('exct float', lambda: ident(W, 1, 1, exct=[0.5]),
     TypeError, 'exct must be a sequence of variable indices'),
    ('exct str', lambda: ident(W, 1, 1, exct="0"),
     TypeError, 'exct must be a sequence of variable indices'),
    ('wini scalar 1', lambda: ident(W, 1, 1, wini=1),
     ValueError, 'wini must be None, 0, or ell x q.*scalar 1'),
    ('wini shape', lambda: ident(W, 1, 1, wini=[np.zeros((2,3))]),
     ValueError, 'wini\\[0\\] must be ell x q = 1 x 3, got shape \\(2, 3\\)'),
    ('wini count', lambda: ident(W, 1, 1, wini=[0,0]),
     ValueError, 'wini has 2 entries but w has N = 1 series'),
    ('wini nan', lambda: ident(W, 1, 1, wini=[np.full((1,3),np.nan)]),
     ValueError, 'wini\\[0\\] holds 3 non-finite'),
    ('wini 3d wrong', lambda: ident(W, 1, 1, wini=np.zeros((1,3,2))),
     ValueError, 'wini has 2 entries but w has N = 1 series'),
    ('sys0 wrong', lambda: ident(W, 1, 2, sys0=SYS),
     ValueError, 'sys0 must have m = 1 inputs, p = 2 outputs and order ell\\*p = 4; got 1 inputs, 2 outputs, order 2'),
    ('sys0 type', lambda: ident(W, 1, 1, sys0="abc"),
     TypeError, 'sys0 must be a control.StateSpace or a kernel parameter R'),
    ('sys0 continuous', lambda: ident(W, 1, 1, sys0=control.ss(SYS.A, SYS.B, SYS.C, SYS.D)),
     ValueError, 'sys0 must be a discrete-time model'),
    ('maxiter neg', lambda: ident(W, 1, 1, maxiter=-1),
     ValueError, 'maxiter must satisfy 0 <= maxiter, got -1'),
    ('maxiter float', lambda: ident(W, 1, 1, maxiter=1.5),
     TypeError, 'maxiter must be an integer, got 1.5'),
    ('tol nan', lambda: ident(W, 1, 1, tol=float('nan')),
     ValueError, 'tol must be a finite positive number, got nan'),
    ('tol inf', lambda: ident(W, 1, 1, tol=float('inf')),
     ValueError, 'tol must be a finite positive number, got inf'),
    ('tol neg', lambda: ident(W, 1, 1, tol=-1),
     ValueError, 'tol must be a finite positive number, got -1'),
    ('disp bad', lambda: ident(W, 1, 1, disp="loud"),
     ValueError, "disp must be one of .*got 'loud'"),
    ('unknown kw', lambda: ident(W, 1, 1, foo=1),
     TypeError, "unexpected keyword argument 'foo'"),
    ('too short', lambda: ident(W[:3], 1, 1),
     ValueError, 'w is too short for the model class m = 1, ell = 1.*give at least'),
    ('misfit not ss', lambda: misfit(W, "sys"),
     TypeError, 'sysh must be a control.StateSpace, got str'),
    ('misfit tf', lambda: misfit(W, control.tf([1],[1,0.5],1)),
     TypeError, 'sysh must be a control.StateSpace, got TransferFunction'),
    ('misfit q mismatch', lambda: misfit(W[:, :2], SYS),
     ValueError, 'sysh has 1 inputs and 2 outputs but w has q = 2 variables'),
    ('misfit continuous', lambda: misfit(W, control.ss(SYS.A, SYS.B, SYS.C, SYS.D)),
     ValueError, 'sysh must be a discrete-time model'),
    ('misfit unknown kw', lambda: misfit(W, SYS, bar=2),
     TypeError, "unexpected keyword argument 'bar'"),
    ('misfit nan', lambda: misfit(W_WITH_INF, SYS),
     ValueError, 'w holds 1 non-finite value'),
    ('misfit wini shape', lambda: misfit(W, SYS, wini=[np.zeros((3,3))]),
     ValueError, 'wini\\[0\\] must be ell x q = 1 x 3, got shape \\(3, 3\\)'),
    # the general solver and its structure
    ("Structure depths", lambda: Structure((0, 2), (10,)), ValueError, "depths"),
    ("Structure n_cols", lambda: Structure((2, 2), (0,)), ValueError, "n_cols"),
    ("Structure perm", lambda: Structure((2, 2), (10,), perm=(0, 0, 1, 2)), ValueError, "perm must be a permutation"),
    ("Structure weights length", lambda: Structure((2, 2), (10,), weights=np.ones(3)), ValueError, "weights must have length n_params = 22, got 3"),
    ("Structure weights negative", lambda: Structure((2, 2), (10,), weights=-np.ones(22)), ValueError, "weights must be positive"),
    ("slra p length", lambda: slra(P[:-1], STRUCTURE, 5), ValueError, "p must have length"),
    ("slra rank", lambda: slra(P, STRUCTURE, 6), ValueError, "rank must be"),
    ("slra p nan", lambda: slra(np.where(np.arange(P.size) == 3, np.nan, P), STRUCTURE, 5), ValueError, "p must be finite"),
    ("slra disp", lambda: slra(P, STRUCTURE, 5, disp="loud"), ValueError, "disp must be"),
    ("slra R0 shape", lambda: slra(P, STRUCTURE, 5, R0=np.ones((1, 5))), ValueError, "R must have d = 6 columns, got 5"),
    ("kernel_misfit R rank", lambda: kernel_misfit(P, STRUCTURE, np.ones((2, 6))), ValueError, "full row rank"),
]


@pytest.mark.parametrize("name, call, error, words", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_refused_clearly(name, call, error, words) -> None:
    with pytest.raises(error, match=words) as caught:
        call()
    origin = traceback.extract_tb(caught.value.__traceback__)[-1].filename
    assert not any(f"{os.sep}{lib}{os.sep}" in origin for lib in ("numpy", "scipy", "control")), origin


def test_catalogue_is_large() -> None:
    assert len(CASES) >= 40


def test_inputs_are_not_modified_and_outputs_do_not_alias_them() -> None:
    rng = np.random.default_rng(3)
    w = rng.standard_normal((80, 3))
    series = [w[:50].copy(), w[50:].copy()]
    wini = [np.zeros((1, 3)), None]
    copies = (w.copy(), [s.copy() for s in series], [x if x is None else x.copy() for x in wini])
    sysh, info, wh, _ = ident(w, 1, 1, exct=[0])
    assert not np.shares_memory(wh, w)
    _, _, wh_list, _ = ident(series, 1, 1, wini=wini)
    assert all(not np.shares_memory(a, b) for a, b in zip(wh_list, series))
    _, wh_m, _ = misfit(w, sysh)
    assert not np.shares_memory(wh_m, w)
    np.testing.assert_array_equal(w, copies[0])
    for s, c in zip(series, copies[1]):
        np.testing.assert_array_equal(s, c)
    np.testing.assert_array_equal(wini[0], copies[2][0])
