"""The rule for warnings inside tests (conftest.warnings_as_errors, recorded_warnings): a dependency's
deprecation warnings are not our errors; ours, and every other warning, are."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from conftest import recorded_warnings, warnings_as_errors
from ident.representations import kernel_to_ss


def warner_in(module: str, category=DeprecationWarning):
    """A function defined in `module` (by name) that warns about its caller's line, as numpy does when
    a deprecated thing is used: the warning is attributed to the module that used it."""
    namespace = {"__name__": module, "warnings": warnings}
    exec(compile("def used_deprecated(category):\n"
                 "    warnings.warn('Setting the shape on a NumPy array has been deprecated', category, "
                 "stacklevel=1)\n", f"<{module}>", "exec"), namespace)
    return lambda: namespace["used_deprecated"](category)


@pytest.mark.parametrize("module", ["control.statesp", "scipy.signal", "numpy.linalg", "matplotlib.pyplot"])
def test_a_dependencys_deprecation_is_not_an_error(module) -> None:
    with warnings_as_errors():
        warner_in(module)()
        warner_in(module, PendingDeprecationWarning)()
    with recorded_warnings() as caught:
        warner_in(module)()
    assert caught == []


@pytest.mark.parametrize("module", ["ident.representations", "ident", "test_warning_rules"])
def test_our_deprecations_are_errors(module) -> None:
    with warnings_as_errors(), pytest.raises(DeprecationWarning, match="deprecated"):
        warner_in(module)()
    with recorded_warnings() as caught:
        warner_in(module)()
    assert [w.category for w in caught] == [DeprecationWarning]


def test_our_deprecations_fail_any_test() -> None:
    # pyproject's filterwarnings: outside any warnings context of the test's own
    with pytest.raises(DeprecationWarning):
        warner_in("ident.representations")()
    with warnings.catch_warnings(record=True) as caught:  # the filters kept, the warnings recorded
        warner_in("identity")()  # a module whose name only begins like ours: a warning, not an error
        warner_in("control.statesp")()  # a dependency's
    assert [w.category for w in caught] == [DeprecationWarning] * 2


def test_a_dependencys_other_warnings_are_errors() -> None:
    with warnings_as_errors(), pytest.raises(RuntimeWarning):
        warner_in("control.statesp", RuntimeWarning)()


def test_python_control_deprecating_under_a_newer_numpy(monkeypatch) -> None:
    # what numpy 2.5 does to python-control 0.10.2: control.ss sets an array's shape, numpy warns,
    # and the warning is control's; the test of a well-conditioned conversion must still pass
    import control
    original, deprecated = control.ss, warner_in("control.statesp")

    def ss(*args, **kwargs):
        deprecated()
        return original(*args, **kwargs)

    monkeypatch.setattr(control, "ss", ss)
    R = np.array([[0.3, 1.0, 0.2, -1.0]])  # m = 1, ell = 1, P_1 = 1
    with warnings_as_errors():
        kernel_to_ss(R, 1, 1)
    with pytest.warns(DeprecationWarning):  # it was raised, and only filtered by the rule
        kernel_to_ss(R, 1, 1)
