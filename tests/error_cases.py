"""Catalogue of malformed inputs across the public API and the typed error each must raise.

Every entry is an :class:`ErrorCase`: an id, a description of the bad input, the call as
shown in ``docs/errors.md``, a zero-argument callable that must raise, the expected
exception class and ``hint``, a fragment that the message must contain (case-insensitive):
the part that tells the user what to change.

Used by ``tests/test_error_table.py`` (runs every case) and ``docs/gen_errors.py`` (writes
``docs/errors.md`` with the real messages). Data are small and deterministic (the chapter's
example at ``output_bound = 0.05``, ``N = 40``, ``random_state = 0``), so the table is
reproducible.
"""

from __future__ import annotations

import functools
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from sklearn.exceptions import NotFittedError

import hammerbound as hb
from hammerbound.exceptions import (
    DataScaleError,
    DataValidationError,
    IllPosedBacklashError,
    NotEnoughAmplitudesError,
    OutputExistsError,
    OutputPathError,
    ParameterValidationError,
    RelaxationTooLargeError,
    ResultOneViolationError,
    SolverNotAvailableError,
    SolverOptionError,
)

#: CSV files of the io cases are written here; docs/gen_errors.py shows it as ``<tmp>``.
CSV_DIR = Path(tempfile.gettempdir()) / "hammerbound-error-cases"


@dataclass(frozen=True)
class ErrorCase:
    id: str
    area: str
    description: str
    call: str
    func: Callable[[], object]
    expected: type
    hint: str


# ------------------------------------------------------------------------------ data
@functools.cache
def example():
    return hb.chapter_example(0.05, N=40, random_state=0)


def u_ss():
    return example().steady.u.copy()


def y_ss():
    return example().steady.y.copy()


def u_prbs():
    return example().prbs.u.copy()


def y_prbs():
    return example().prbs.y.copy()


def x_inner():
    """The true inner signal of the PRBS experiment (stage-2 data without stage 1)."""
    return example().prbs.x.copy()


@functools.cache
def stage1():
    return hb.BacklashSetEstimator(0.05).fit(u_ss(), y_ss())


@functools.cache
def stage2():
    return hb.LinearEIVSetEstimator(2, 2, output_bound=0.05, method="lp").fit(x_inner(), y_prbs())


@functools.cache
def identified():
    return hb.HammersteinBacklashIdentifier(hb.BacklashSetEstimator(0.05), lin()).fit(
        u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss()))


def lin(**kw):
    kw = {"na": 2, "nb": 2, "output_bound": 0.05, "method": "lp", **kw}
    return hb.LinearEIVSetEstimator(**kw)


def ident(**kw):
    """The identifier with both stage estimators given (``bl``, ``lin`` in the table)."""
    kw = {"backlash": hb.BacklashSetEstimator(0.05), "linear": lin(), **kw}
    return hb.HammersteinBacklashIdentifier(**kw)


def with_value(a, i, v):
    a = np.array(a, dtype=float)
    a[i] = v
    return a


def csv_file(name, text: str | bytes) -> Path:
    CSV_DIR.mkdir(parents=True, exist_ok=True)
    p = CSV_DIR / name
    if isinstance(text, bytes):
        p.write_bytes(text)
    else:
        p.write_text(text)
    return p


def read(name, text, columns=("u", "y")):
    from hammerbound.data.csv_reader import read_columns

    return read_columns(csv_file(name, text), list(columns))


SYS = hb.HammersteinSystem(hb.Backlash(0.25, 0.0628, 0.26, 0.0489),
                           ([1.0, -0.76, 0.82], [0.0, 2.15, -1.09]))


def _diagnose(*args, **kw):
    from hammerbound.discrepancy import diagnose

    return diagnose(*args, **kw)


def _tf(*args):
    import control

    return control.tf(*args)


C = ErrorCase
CASES: list[ErrorCase] = [
    # ------------------------------------------------------------- stage 1: backlash
    C("s1-no-output-bound", "stage 1", "no output error bound",
      "BacklashSetEstimator().fit(u_ss, y_ss)",
      lambda: hb.BacklashSetEstimator().fit(u_ss(), y_ss()),
      ParameterValidationError, "BacklashSetEstimator(output_bound="),
    C("s1-nan-output", "stage 1", "NaN in the steady-state outputs",
      "BacklashSetEstimator(0.05).fit(u_ss, y_ss with y_ss[3] = nan)",
      lambda: hb.BacklashSetEstimator(0.05).fit(u_ss(), with_value(y_ss(), 3, np.nan)),
      DataValidationError, "drop those points"),
    C("s1-inf-input", "stage 1", "infinite steady-state input",
      "BacklashSetEstimator(0.05).fit(u_ss with u_ss[0] = inf, y_ss)",
      lambda: hb.BacklashSetEstimator(0.05).fit(with_value(u_ss(), 0, np.inf), y_ss()),
      DataValidationError, "infinity"),
    C("s1-length-mismatch", "stage 1", "inputs and outputs of different lengths",
      "BacklashSetEstimator(0.05).fit(u_ss, y_ss[:-1])",
      lambda: hb.BacklashSetEstimator(0.05).fit(u_ss(), y_ss()[:-1]),
      DataValidationError, "inconsistent numbers of samples"),
    C("s1-empty", "stage 1", "empty arrays",
      "BacklashSetEstimator(0.05).fit([], [])",
      lambda: hb.BacklashSetEstimator(0.05).fit([], []),
      DataValidationError, "0 sample"),
    C("s1-two-columns", "stage 1", "inputs with two columns",
      "BacklashSetEstimator(0.05).fit(np.c_[u_ss, u_ss], y_ss)",
      lambda: hb.BacklashSetEstimator(0.05).fit(np.c_[u_ss(), u_ss()], y_ss()),
      DataValidationError, "reshape"),
    C("s1-complex", "stage 1", "complex-valued inputs (wrong dtype)",
      "BacklashSetEstimator(0.05).fit(u_ss + 0j, y_ss)",
      lambda: hb.BacklashSetEstimator(0.05).fit(u_ss() + 1j, y_ss()),
      DataValidationError, "must be real numbers"),
    C("s1-strings", "stage 1", "text instead of numbers (wrong dtype)",
      "BacklashSetEstimator(0.05).fit(['1.0', 'a'], [0.1, 0.2])",
      lambda: hb.BacklashSetEstimator(0.05).fit(["1.0", "a"], [0.1, 0.2]),
      DataValidationError, "numeric"),
    C("s1-noise-zero", "stage 1", "zero output error bound",
      "BacklashSetEstimator(output_bound=0).fit(u_ss, y_ss)",
      lambda: hb.BacklashSetEstimator(0.0).fit(u_ss(), y_ss()),
      ParameterValidationError, "> 0"),
    C("s1-noise-negative", "stage 1", "negative output error bound",
      "BacklashSetEstimator(output_bound=-0.05).fit(u_ss, y_ss)",
      lambda: hb.BacklashSetEstimator(-0.05).fit(u_ss(), y_ss()),
      ParameterValidationError, "> 0"),
    C("s1-noise-length", "stage 1", "per-sample output error bound of the wrong length",
      "BacklashSetEstimator(output_bound=[0.05] * 3).fit(u_ss, y_ss)",
      lambda: hb.BacklashSetEstimator([0.05] * 3).fit(u_ss(), y_ss()),
      ParameterValidationError, "one value per sample"),
    C("s1-noise-text", "stage 1", "output error bound given as text",
      "BacklashSetEstimator(output_bound='small').fit(u_ss, y_ss)",
      lambda: hb.BacklashSetEstimator("small").fit(u_ss(), y_ss()),
      ParameterValidationError, "number"),
    C("s1-method", "stage 1", "unknown stage-1 method",
      "BacklashSetEstimator(0.05, method='simplex').fit(u_ss, y_ss)",
      lambda: hb.BacklashSetEstimator(0.05, method="simplex").fit(u_ss(), y_ss()),
      ParameterValidationError, "'polygon' or 'algorithm'"),
    C("s1-zero-input", "stage 1", "a steady-state input equal to 0 (belongs to no line)",
      "BacklashSetEstimator(0.05).fit(u_ss with u_ss[4] = 0, y_ss)",
      lambda: hb.BacklashSetEstimator(0.05).fit(with_value(u_ss(), 4, 0.0), y_ss()),
      DataValidationError, "non-zero"),
    C("s1-one-amplitude", "stage 1", "too few amplitudes: one square wave only",
      "BacklashSetEstimator(0.05).fit(u_ss[:2], y_ss[:2])",
      lambda: hb.BacklashSetEstimator(0.05).fit(u_ss()[:2], y_ss()[:2]),
      NotEnoughAmplitudesError, "at least two different negative amplitudes"),
    C("s1-one-side", "stage 1", "too few amplitudes: no negative half-waves",
      "BacklashSetEstimator(0.05).fit(u_ss[u_ss > 0], y_ss[u_ss > 0])",
      lambda: hb.BacklashSetEstimator(0.05).fit(u_ss()[u_ss() > 0], y_ss()[u_ss() > 0]),
      NotEnoughAmplitudesError, "left side"),
    C("s1-not-fitted", "stage 1", "result requested before fit",
      "BacklashSetEstimator(0.05).suggest_prbs_level()",
      lambda: hb.BacklashSetEstimator(0.05).suggest_prbs_level(),
      NotFittedError, "call 'fit'"),
    C("s1-ustar-dead-zone", "stage 1", "PRBS level u* inside the dead zone (Result 1)",
      "stage1.check_prbs_level(0.03)",
      lambda: stage1().check_prbs_level(0.03),
      ResultOneViolationError, "choose u* in"),
    C("s1-ustar-crossing", "stage 1", "PRBS level u* past the crossing of the backlash lines",
      "stage1.check_prbs_level(3.0)",
      lambda: stage1().check_prbs_level(3.0),
      ResultOneViolationError, "choose u* in"),
    C("s1-ustar-nan", "stage 1", "non-finite PRBS level",
      "stage1.check_prbs_level(nan)",
      lambda: stage1().check_prbs_level(float("nan")),
      ParameterValidationError, "finite number > 0"),
    C("s1-ustar-none", "stage 1", "PRBS level of the wrong type",
      "stage1.check_prbs_level(None)",
      lambda: stage1().check_prbs_level(None),
      ParameterValidationError, "finite number > 0"),
    C("s1-margin", "stage 1", "margin outside (0, 1)",
      "stage1.suggest_prbs_level(margin=1.5)",
      lambda: stage1().suggest_prbs_level(margin=1.5),
      ParameterValidationError, "(0, 1)"),
    C("s1-inner-three-levels", "stage 1", "inner signal asked for a non-PRBS input",
      "stage1.inner_signal(np.r_[u_prbs, 0.5], u_star=1.0)",
      lambda: stage1().inner_signal(np.r_[u_prbs(), 0.5], u_star=1.0),
      DataValidationError, "two-level input"),
    # ------------------------------------------------------------- stage 2: linear EIV
    C("s2-nan-input", "stage 2", "NaN in the central inner signal",
      "LinearEIVSetEstimator(...).fit(x with x[5] = nan, y)",
      lambda: lin().fit(with_value(x_inner(), 5, np.nan), y_prbs()),
      DataValidationError, "dropping one joins two parts"),
    C("s2-inf-output", "stage 2", "infinite output sample",
      "LinearEIVSetEstimator(...).fit(x, y with y[7] = -inf)",
      lambda: lin().fit(x_inner(), with_value(y_prbs(), 7, -np.inf)),
      DataValidationError, "sample 7"),
    C("s2-length-mismatch", "stage 2", "input and output of different lengths",
      "LinearEIVSetEstimator(...).fit(x, y[:-3])",
      lambda: lin().fit(x_inner(), y_prbs()[:-3]),
      DataValidationError, "same number of samples"),
    C("s2-empty", "stage 2", "empty arrays",
      "LinearEIVSetEstimator(...).fit([], [])",
      lambda: lin().fit([], []),
      DataValidationError, "at least one sample"),
    C("s2-two-columns", "stage 2", "2-D input with two columns",
      "LinearEIVSetEstimator(...).fit(np.c_[x, x], y)",
      lambda: lin().fit(np.c_[x_inner(), x_inner()], y_prbs()),
      DataValidationError, "shape (N,) or (N, 1)"),
    C("s2-ragged", "stage 2", "ragged nested list",
      "LinearEIVSetEstimator(...).fit([[1.0], [1.0, 2.0]], [0.1, 0.2])",
      lambda: lin().fit([[1.0], [1.0, 2.0]], [0.1, 0.2]),
      DataValidationError, "1-D array of real numbers"),
    C("s2-text", "stage 2", "text instead of numbers (wrong dtype)",
      "LinearEIVSetEstimator(...).fit(['a'] * 5, [0.0] * 5)",
      lambda: lin().fit(["a"] * 5, [0.0] * 5),
      DataValidationError, "real numbers"),
    C("s2-too-short", "stage 2", "fewer samples than the model order needs",
      "LinearEIVSetEstimator(na=2, nb=2, ...).fit(x[:3], y[:3])",
      lambda: lin().fit(x_inner()[:3], y_prbs()[:3]),
      DataValidationError, "Use a longer record (N >= 6)"),
    C("s2-noise-zero", "stage 2", "zero output error bound",
      "LinearEIVSetEstimator(output_bound=0, ...).fit(x, y)",
      lambda: lin(output_bound=0.0).fit(x_inner(), y_prbs()),
      ParameterValidationError, "must be > 0"),
    C("s2-noise-none", "stage 2", "no output error bound",
      "LinearEIVSetEstimator(na=2, nb=2).fit(x, y)",
      lambda: lin(output_bound=None).fit(x_inner(), y_prbs()),
      ParameterValidationError, "LinearEIVSetEstimator(output_bound="),
    C("s2-noise-length", "stage 2", "per-sample output error bound of the wrong length",
      "LinearEIVSetEstimator(output_bound=[0.05, 0.05], ...).fit(x, y)",
      lambda: lin(output_bound=[0.05, 0.05]).fit(x_inner(), y_prbs()),
      DataValidationError, "one value per sample"),
    C("s2-input-bound-negative", "stage 2", "negative input bound",
      "LinearEIVSetEstimator(...).fit(x, y, input_bound=-0.01)",
      lambda: lin().fit(x_inner(), y_prbs(), input_bound=-0.01),
      ParameterValidationError, ">= 0"),
    C("s2-order-negative", "stage 2", "negative model order",
      "LinearEIVSetEstimator(na=-1, ...).fit(x, y)",
      lambda: lin(na=-1).fit(x_inner(), y_prbs()),
      ParameterValidationError, "integer >= 0"),
    C("s2-order-float", "stage 2", "non-integer model order",
      "LinearEIVSetEstimator(nb=1.5, ...).fit(x, y)",
      lambda: lin(nb=1.5).fit(x_inner(), y_prbs()),
      ParameterValidationError, "integer >= 0"),
    C("s2-no-b", "stage 2", "wrong-order model: numerator without coefficients",
      "LinearEIVSetEstimator(nb=0, nk=1, ...).fit(x, y)",
      lambda: lin(nb=0).fit(x_inner(), y_prbs()),
      ParameterValidationError, "nb >= 1 or nk=0"),
    C("s2-nk-text", "stage 2", "input delay given as text",
      "LinearEIVSetEstimator(nk='1', ...).fit(x, y)",
      lambda: lin(nk="1").fit(x_inner(), y_prbs()),
      ParameterValidationError, "integer >= 0"),
    C("s2-orders-too-high", "stage 2", "more parameters than the methods support",
      "LinearEIVSetEstimator(na=40, nb=40, ...).fit(x, y) with N = 40",
      lambda: lin(na=40, nb=40).fit(x_inner(), y_prbs()),
      ParameterValidationError, "orders up to na = nb ="),
    C("s2-record-too-short", "stage 2", "fewer equations than parameters",
      "LinearEIVSetEstimator(na=6, nb=6, ...).fit(x[:15], y[:15])",
      lambda: lin(na=6, nb=6).fit(x_inner()[:15], y_prbs()[:15]),
      DataValidationError, "orders up to na = nb = 5"),
    C("s2-method", "stage 2", "unknown stage-2 method",
      "LinearEIVSetEstimator(method='sdp', ...).fit(x, y)",
      lambda: lin(method="sdp").fit(x_inner(), y_prbs()),
      ParameterValidationError, "one of"),
    C("s2-relaxation-order", "stage 2", "relaxation order 0",
      "LinearEIVSetEstimator(method='moment', relaxation_order=0, ...).fit(x, y)",
      lambda: lin(method="moment", relaxation_order=0).fit(x_inner(), y_prbs()),
      ParameterValidationError, "integer >= 1"),
    C("s2-unknown-solver", "stage 2", "unknown solver",
      "LinearEIVSetEstimator(method='moment', solver='gurobi', ...).fit(x, y)",
      lambda: lin(method="moment", solver="gurobi").fit(x_inner(), y_prbs()),
      SolverNotAvailableError, "available solvers"),
    C("s2-solver-options-type", "stage 2", "solver options not a dict",
      "LinearEIVSetEstimator(method='moment', solver_options=[('max_iter', 5)], ...)"
      ".fit(x, y)",
      lambda: lin(method="moment", solver_options=[("max_iter", 5)]).fit(x_inner(), y_prbs()),
      SolverOptionError, "must be a dict"),
    C("s2-solver-option-unknown", "stage 2", "option of another solver",
      "LinearEIVSetEstimator(method='moment', solver='cvxopt', solver_options={'max_iter': 5},"
      " ...).fit(x, y)",
      lambda: lin(method="moment", solver="cvxopt",
                  solver_options={"max_iter": 5}).fit(x_inner(), y_prbs()),
      SolverOptionError, "valid:"),
    C("s2-solver-option-value", "stage 2", "solver option of the wrong type",
      "LinearEIVSetEstimator(method='moment', solver='cvxopt', "
      "solver_options={'maxiters': 'ten'}, ...).fit(x, y)",
      lambda: lin(method="moment", solver="cvxopt",
                  solver_options={"maxiters": "ten"}).fit(x_inner(), y_prbs()),
      SolverOptionError, "must be an int"),
    C("s2-on-failure", "stage 2", "unknown on_failure policy",
      "LinearEIVSetEstimator(on_failure='ignore', ...).fit(x, y)",
      lambda: lin(on_failure="ignore").fit(x_inner(), y_prbs()),
      ParameterValidationError, "'box' or 'raise'"),
    C("s2-max-nodes", "stage 2", "node limit given as text",
      "LinearEIVSetEstimator(method='exact', max_nodes='many', ...).fit(x, y)",
      lambda: lin(method="exact", max_nodes="many").fit(x_inner(), y_prbs()),
      ParameterValidationError, "integer >= 0"),
    C("s2-theta-box-shape", "stage 2", "a priori box of the wrong shape",
      "LinearEIVSetEstimator(theta_box=np.ones((3, 2)), ...).fit(x, y)",
      lambda: lin(theta_box=np.ones((3, 2))).fit(x_inner(), y_prbs()),
      ParameterValidationError, "shape (4, 2)"),
    C("s2-theta-box-text", "stage 2", "a priori box given as text",
      "LinearEIVSetEstimator(theta_box='wide', ...).fit(x, y)",
      lambda: lin(theta_box="wide").fit(x_inner(), y_prbs()),
      ParameterValidationError, "shape (4, 2)"),
    C("s2-gain-zero", "stage 2", "zero steady-state gain (A2)",
      "LinearEIVSetEstimator(steady_state_gain=0, ...).fit(x, y)",
      lambda: lin(steady_state_gain=0).fit(x_inner(), y_prbs()),
      ParameterValidationError, "non-zero number or None"),
    C("s2-groups-float", "stage 2", "non-integer input-error groups",
      "LinearEIVSetEstimator(...).fit(x, y, input_groups=np.full(N, 0.5))",
      lambda: lin().fit(x_inner(), y_prbs(), input_groups=np.full(40, 0.5)),
      DataValidationError, "integer array of shape (N,)"),
    C("s2-n-jobs", "stage 2", "n_jobs = 0",
      "LinearEIVSetEstimator(n_jobs=0, ...).fit(x, y)",
      lambda: lin(n_jobs=0).fit(x_inner(), y_prbs()),
      ParameterValidationError, "positive integer or -1"),
    C("s2-contains-shape", "stage 2", "parameter vector of the wrong length",
      "stage2.contains([1.0, 2.0])",
      lambda: stage2().contains([1.0, 2.0]),
      DataValidationError, "in order"),
    # ------------------------------------------------------------- both stages
    C("h-no-steady-state", "identifier", "two-stage procedure without steady-state data",
      "HammersteinBacklashIdentifier(bl, lin, procedure='two-stage').fit(u_prbs, y_prbs)",
      lambda: ident(procedure="two-stage").fit(u_prbs(), y_prbs()),
      DataValidationError, "pass steady_state="),
    C("h-one-record-moment", "identifier", "one record with the moment method",
      "HammersteinBacklashIdentifier(linear=LinearEIVSetEstimator(method='moment', ...)).fit(u, y)",
      lambda: ident(linear=lin(method="moment")).fit(u_prbs(), y_prbs()),
      ParameterValidationError, "method='exact'"),
    C("h-one-record-constant-input", "identifier", "one record with a constant input",
      "HammersteinBacklashIdentifier(linear=lin, procedure='one-record').fit(ones(40), y_prbs)",
      lambda: ident(procedure="one-record").fit(np.ones(40), y_prbs()),
      DataValidationError, "must move the input"),
    C("h-procedure", "identifier", "unknown procedure",
      "HammersteinBacklashIdentifier(bl, lin, procedure='joint').fit(u, y)",
      lambda: ident(procedure="joint").fit(u_prbs(), y_prbs()),
      ParameterValidationError, "procedure must be one of"),
    C("h-gamma-box", "identifier", "malformed a priori backlash box",
      "HammersteinBacklashIdentifier(bl, lin, gamma_box=[[0, 1]]).fit(u, y)",
      lambda: ident(gamma_box=[[0, 1]]).fit(u_prbs(), y_prbs()),
      ParameterValidationError, "gamma_box must be"),
    C("h-steady-state-dict", "identifier", "steady-state dict with wrong keys",
      "HammersteinBacklashIdentifier(bl, lin).fit(u_prbs, y_prbs, steady_state={'x': u_ss})",
      lambda: ident().fit(u_prbs(), y_prbs(),
                          steady_state={"x": u_ss()}),
      DataValidationError, "keys 'u' and 'y'"),
    C("h-prbs-three-levels", "identifier", "two-stage procedure, PRBS with more than two levels",
      "HammersteinBacklashIdentifier(bl, lin, procedure='two-stage').fit(u_prbs with u[0] = 0.5, "
      "y_prbs, steady_state=...)",
      lambda: ident(procedure="two-stage").fit(
          with_value(u_prbs(), 0, 0.5), y_prbs(), steady_state=(u_ss(), y_ss())),
      DataValidationError, "ordinary record"),
    C("h-constant-input-steady", "identifier",
      "constant input with steady-state data (procedure 'auto')",
      "HammersteinBacklashIdentifier(bl, lin).fit(ones_like(u_prbs), y_prbs, steady_state=...)",
      lambda: ident().fit(np.ones_like(u_prbs()), y_prbs(), steady_state=(u_ss(), y_ss())),
      DataValidationError, "the input is constant"),
    C("h-length-mismatch", "identifier", "PRBS input and output of different lengths",
      "HammersteinBacklashIdentifier(bl, lin).fit(u_prbs, y_prbs[:-1], steady_state=...)",
      lambda: ident().fit(u_prbs(), y_prbs()[:-1],
                          steady_state=(u_ss(), y_ss())),
      DataValidationError, "same number of samples"),
    C("h-ustar-dead-zone", "identifier", "PRBS level u* inside the dead zone",
      "HammersteinBacklashIdentifier(bl, lin).fit(0.03 * sign(u_prbs), y_prbs, steady_state=...)",
      lambda: ident().fit(
          0.03 * np.sign(u_prbs()), y_prbs(), steady_state=(u_ss(), y_ss())),
      ResultOneViolationError, "dead zone"),
    C("h-ustar-crossing", "identifier", "PRBS level u* past the line crossing",
      "HammersteinBacklashIdentifier(bl, lin, prbs_level=3.0).fit(3 * sign(u_prbs), y_prbs, "
      "steady_state=...)",
      lambda: ident(prbs_level=3.0).fit(
          3.0 * np.sign(u_prbs()), y_prbs(), steady_state=(u_ss(), y_ss())),
      ResultOneViolationError, "crossing"),
    C("h-prbs-level-text", "identifier", "prbs_level given as text",
      "HammersteinBacklashIdentifier(bl, lin, prbs_level='one').fit(u_prbs, y_prbs, steady_state=...)",
      lambda: ident(prbs_level="one").fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "number u* > 0"),
    C("h-inner-signal", "identifier", "unknown inner-signal model",
      "HammersteinBacklashIdentifier(bl, lin, inner_signal='three-level').fit(...)",
      lambda: ident(inner_signal="three-level").fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "one of"),
    C("h-components", "identifier", "stage estimators swapped",
      "HammersteinBacklashIdentifier(backlash=LinearEIVSetEstimator()).fit(...)",
      lambda: ident(backlash=hb.LinearEIVSetEstimator()).fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "backlash must be a BacklashSetEstimator instance"),
    C("h-class-not-instance", "identifier", "the estimator class instead of an instance",
      "HammersteinBacklashIdentifier(bl, linear=LinearEIVSetEstimator).fit(...)",
      lambda: ident(linear=hb.LinearEIVSetEstimator).fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "Pass e.g. linear=LinearEIVSetEstimator("),
    C("h-method-name-as-estimator", "identifier", "a method name in place of an estimator",
      "HammersteinBacklashIdentifier(backlash='polygon', linear=lin).fit(...)",
      lambda: ident(backlash="polygon").fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "go to the BacklashSetEstimator"),
    C("h-no-output-bound", "identifier", "no stage estimators (no output error bound)",
      "HammersteinBacklashIdentifier().fit(u_prbs, y_prbs, steady_state=...)",
      lambda: hb.HammersteinBacklashIdentifier().fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "pass backlash=BacklashSetEstimator(output_bound="),
    C("h-no-stage2-bound", "identifier", "stage-2 estimator without an output error bound",
      "HammersteinBacklashIdentifier(bl, LinearEIVSetEstimator()).fit(...)",
      lambda: ident(linear=hb.LinearEIVSetEstimator()).fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "fit(..., output_bound=...)"),
    # ------------------------------------------------------------- systems
    C("sys-backlash-negative", "systems", "negative backlash slope",
      "Backlash(-0.25, 0.06, 0.26, 0.05)",
      lambda: hb.Backlash(-0.25, 0.06, 0.26, 0.05),
      ParameterValidationError, "finite number > 0"),
    C("sys-backlash-nan", "systems", "NaN dead-zone width",
      "Backlash(0.25, nan, 0.26, 0.05)",
      lambda: hb.Backlash(0.25, float("nan"), 0.26, 0.05),
      ParameterValidationError, "finite number > 0"),
    C("sys-unstable", "systems", "non-stable linear block (A1)",
      "HammersteinSystem(backlash, ([1, -1.5], [0, 1]))",
      lambda: hb.HammersteinSystem(SYS.backlash, ([1.0, -1.5], [0.0, 1.0])),
      ParameterValidationError, "not asymptotically stable"),
    C("sys-non-finite", "systems", "non-finite transfer-function coefficient",
      "HammersteinSystem(backlash, ([1, -0.5], [0, inf]))",
      lambda: hb.HammersteinSystem(SYS.backlash, ([1.0, -0.5], [0.0, np.inf])),
      ParameterValidationError, "must be finite"),
    C("sys-continuous", "systems", "continuous-time transfer function",
      "HammersteinSystem(backlash, control.tf([1], [1, 1]))",
      lambda: hb.HammersteinSystem(SYS.backlash, _tf([1.0], [1.0, 1.0])),
      ParameterValidationError, "control.sample_system"),
    C("sys-improper", "systems", "wrong-order (improper) transfer function",
      "HammersteinSystem(backlash, control.tf([1, 0, 0], [1, 0.5], True))",
      lambda: hb.HammersteinSystem(SYS.backlash, _tf([1.0, 0.0, 0.0], [1.0, 0.5], True)),
      ParameterValidationError, "proper"),
    C("sys-leading-zero", "systems", "A(q^-1) with a zero leading coefficient",
      "HammersteinSystem(backlash, ([0, 1], [0, 1]))",
      lambda: hb.HammersteinSystem(SYS.backlash, ([0.0, 1.0], [0.0, 1.0])),
      ParameterValidationError, "non-zero leading coefficient"),
    C("sys-coefficient-text", "systems", "coefficients given as text",
      "HammersteinSystem(backlash, (['1', 'a'], [0, 1]))",
      lambda: hb.HammersteinSystem(SYS.backlash, (["1", "a"], [0.0, 1.0])),
      ParameterValidationError, "real coefficients"),
    C("sys-not-backlash", "systems", "backlash given as a tuple",
      "HammersteinSystem((0.25, 0.06, 0.26, 0.05), (A, B))",
      lambda: hb.HammersteinSystem((0.25, 0.06, 0.26, 0.05), (SYS.A, SYS.B)),
      ParameterValidationError, "hammerbound.systems.models.Backlash"),
    C("sys-input-past-crossing", "systems", "simulation past the line crossing",
      "system.simulate([1.0, 5.0])",
      lambda: SYS.simulate([1.0, 5.0]),
      IllPosedBacklashError, "keep the input inside"),
    C("sys-gain-zero", "systems", "normalising a zero-gain block (A2)",
      "normalize_gain([1, -0.5], [0, 0])",
      lambda: __import__("hammerbound.systems.models").systems.normalize_gain([1, -0.5], [0, 0]),
      ParameterValidationError, "assumption A2"),
    C("sys-gain-negative", "systems", "negative gain moved into the backlash",
      "normalize_gain([1, -0.5], [0, -1], backlash)",
      lambda: __import__("hammerbound.systems.models").systems.normalize_gain(
          [1, -0.5], [0, -1], SYS.backlash),
      ParameterValidationError, "slopes must stay > 0"),
    # ------------------------------------------------------------- experiments
    C("exp-amplitudes-negative", "experiments", "negative square-wave amplitude",
      "square_wave_experiment(system, [-1.0, 1.0], 0.05)",
      lambda: hb.square_wave_experiment(SYS, [-1.0, 1.0], 0.05),
      DataValidationError, "finite values > 0"),
    C("exp-amplitudes-crossing", "experiments", "square-wave amplitude past the crossing",
      "square_wave_experiment(system, [1.0, 5.0], 0.05)",
      lambda: hb.square_wave_experiment(SYS, [1.0, 5.0], 0.05),
      IllPosedBacklashError, "keep the input inside"),
    C("exp-noise-shape", "experiments", "output error bound of the wrong length",
      "square_wave_experiment(system, [1.0, 2.0], [0.1, 0.2, 0.3])",
      lambda: hb.square_wave_experiment(SYS, [1.0, 2.0], [0.1, 0.2, 0.3]),
      ParameterValidationError, "one value per sample"),
    C("exp-noise-negative", "experiments", "negative output error bound",
      "prbs_experiment(system, 50, 1.0, -0.05)",
      lambda: hb.prbs_experiment(SYS, 50, 1.0, -0.05),
      ParameterValidationError, "finite and >= 0"),
    C("exp-random-state", "experiments", "unusable random_state",
      "prbs_experiment(system, 50, 1.0, 0.05, random_state='seed')",
      lambda: hb.prbs_experiment(SYS, 50, 1.0, 0.05, random_state="seed"),
      ParameterValidationError, "int seed"),
    C("exp-system-type", "experiments", "system that is not a HammersteinSystem",
      "square_wave_experiment((A, B), [1.0, 2.0], 0.05)",
      lambda: hb.square_wave_experiment((SYS.A, SYS.B), [1.0, 2.0], 0.05),
      ParameterValidationError, "HammersteinSystem(Backlash"),
    C("exp-prbs-length", "experiments", "PRBS of length 0",
      "prbs_experiment(system, 0, 1.0, 0.05)",
      lambda: hb.prbs_experiment(SYS, 0, 1.0, 0.05),
      ParameterValidationError, "positive integers"),
    C("exp-prbs-level-text", "experiments", "PRBS level given as text",
      "prbs_experiment(system, 50, 'high', 0.05)",
      lambda: hb.prbs_experiment(SYS, 50, "high", 0.05),
      ParameterValidationError, "finite number > 0"),
    # ------------------------------------------------------------- CSV input
    C("csv-missing-column", "io", "CSV without the requested column",
      "read_columns('<tmp>/missing.csv', ['u', 'y'])  # header u,z",
      lambda: read("missing.csv", "u,z\n1,2\n"),
      DataValidationError, "rename the columns"),
    C("csv-bad-value", "io", "CSV row with a non-numeric value",
      "read_columns('<tmp>/bad.csv', ['u', 'y'])  # row '1,abc'",
      lambda: read("bad.csv", "u,y\n1,0.5\n1,abc\n"),
      DataValidationError, "line 3, column 'y'"),
    C("csv-short-row", "io", "CSV row with a missing field",
      "read_columns('<tmp>/short.csv', ['u', 'y'])  # row '1'",
      lambda: read("short.csv", "u,y\n1\n"),
      DataValidationError, "line 2"),
    C("csv-non-finite", "io", "CSV with an infinite value",
      "read_columns('<tmp>/inf.csv', ['u', 'y'])  # row '1,inf'",
      lambda: read("inf.csv", "u,y\n1,inf\n"),
      DataValidationError, "not finite"),
    C("csv-empty-file", "io", "empty CSV file",
      "read_columns('<tmp>/empty.csv', ['u', 'y'])",
      lambda: read("empty.csv", ""),
      DataValidationError, "expected a header row"),
    C("csv-no-rows", "io", "CSV with a header only",
      "read_columns('<tmp>/header.csv', ['u', 'y'])",
      lambda: read("header.csv", "u,y\n"),
      DataValidationError, "no data rows"),
    C("csv-no-file", "io", "CSV path that does not exist",
      "read_columns('<tmp>/nope.csv', ['u', 'y'])",
      lambda: __import__("hammerbound.data.csv_reader").data.csv_reader.read_columns(
          CSV_DIR / "nope.csv", ["u", "y"]),
      DataValidationError, "check the path"),
    C("csv-binary", "io", "binary (non-UTF-8) file",
      "read_columns('<tmp>/binary.csv', ['u', 'y'])",
      lambda: read("binary.csv", b"u,y\n\xff\xfe,1\n"),
      DataValidationError, "UTF-8"),
    C("csv-no-columns", "io", "no column names requested",
      "read_columns('<tmp>/ok.csv', [])",
      lambda: read("ok.csv", "u,y\n1,2\n", columns=()),
      DataValidationError, "non-empty list of header names"),
    # ------------------------------------------------------------- discrepancy
    C("diag-continuous", "discrepancy", "continuous-time model",
      "diagnose(control.tf([1], [1, 1]), u_prbs, y_prbs, 0.05)",
      lambda: _diagnose(_tf([1.0], [1.0, 1.0]), u_prbs(), y_prbs(), 0.05),
      ParameterValidationError, "control.sample_system"),
    C("diag-noise-negative", "discrepancy", "negative output error bound",
      "diagnose(system, u_prbs, y_prbs, -1)",
      lambda: _diagnose(SYS, u_prbs(), y_prbs(), -1.0),
      ParameterValidationError, "finite number > 0"),
    C("diag-candidate", "discrepancy", "unknown candidate effect",
      "diagnose(system, u_prbs, y_prbs, 0.05, candidates=['magic'])",
      lambda: _diagnose(SYS, u_prbs(), y_prbs(), 0.05, candidates=["magic"]),
      ParameterValidationError, "choose from"),
    # ------------------------------------------------------------- stage 2: budgets
    C("s2-total-time-negative", "stage 2", "negative total time budget",
      "LinearEIVSetEstimator(method='exact', total_time_limit=-1, ...).fit(x, y)",
      lambda: lin(method="exact", total_time_limit=-1).fit(x_inner(), y_prbs()),
      ParameterValidationError, "seconds >= 0"),
    C("s2-total-time-text", "stage 2", "total time budget given as text",
      "LinearEIVSetEstimator(method='exact', total_time_limit='10', ...).fit(x, y)",
      lambda: lin(method="exact", total_time_limit="10").fit(x_inner(), y_prbs()),
      ParameterValidationError, "None or a number of seconds"),
    C("s2-moment-too-large", "stage 2", "moment relaxation above its size budget",
      "LinearEIVSetEstimator(method='moment', relaxation_order=3, ...).fit(x, y)",
      lambda: lin(method="moment", relaxation_order=3).fit(x_inner(), y_prbs()),
      RelaxationTooLargeError, "(relaxation_max_work; raise it"),
    C("s2-moment-order-8", "stage 2", "moment relaxation of order 8 (refused at once)",
      "LinearEIVSetEstimator(method='moment', relaxation_order=8, ...).fit(x, y)",
      lambda: lin(method="moment", relaxation_order=8).fit(x_inner(), y_prbs()),
      RelaxationTooLargeError, "method='lp'"),
    # ------------------------------------------------------------- output paths (CLI)
    C("output-exists", "io", "output file that exists already (CLI without --force)",
      "check_output_file('<tmp>/results.json', force=False)",
      lambda: _check_output(csv_file("results.json", "{}")),
      OutputExistsError, "pass --force"),
    C("output-no-parent", "io", "output file in a directory that does not exist",
      "check_output_file('<tmp>/no-dir/out.json')",
      lambda: _check_output(CSV_DIR / "no-dir" / "out.json"),
      OutputPathError, "create it first"),
    C("output-is-dir", "io", "a directory given where an output file goes",
      "check_output_file('<tmp>')",
      lambda: _check_output(csv_file("x.csv", "u,y\n").parent),
      OutputPathError, "give a file name"),
    C("report-exists", "io", "report directory holding an earlier report",
      "write_report(ident, ..., '<tmp>/report-dir') (or check_output_dir)",
      lambda: _check_report_dir(),
      OutputExistsError, "pass --force"),
    # ------------------------------------------------------------- model set (issue 16)
    C("modelset-sample-n", "modelset", "zero samples requested",
      "LinearEIVSetEstimator(...).fit(x, y).sample(0)",
      lambda: stage2().sample(0),
      ParameterValidationError, "integer >= 1"),
    C("modelset-omega-order", "modelset", "frequencies not increasing",
      "est.frequency_response_bounds([1.0, 0.5])",
      lambda: stage2().frequency_response_bounds([1.0, 0.5]),
      DataValidationError, "np.unique"),
    C("modelset-dt", "modelset", "sampling time zero",
      "est.frequency_response_bounds(dt=0)",
      lambda: stage2().frequency_response_bounds(dt=0),
      ParameterValidationError, "sampling time > 0"),
    C("modelset-weight-kind", "modelset", "unknown uncertainty kind",
      "est.uncertainty_weight('relative')",
      lambda: stage2().uncertainty_weight("relative"),
      ParameterValidationError, "multiplicative"),
    C("modelset-inverse-range", "modelset", "compensator range past the line crossing",
      "BacklashSetEstimator(0.05).fit(u_ss, y_ss).inverse(v_range=(-50, 50))",
      lambda: stage1().inverse(v_range=(-50.0, 50.0)),
      IllPosedBacklashError, "Narrow v_range"),
    C("modelset-inverse-command", "modelset", "command outside the compensator's range",
      "inv = est.inverse(); inv.compensate([100.0])",
      lambda: stage1().inverse().compensate([100.0]),
      DataValidationError, "wider range"),
    # ------------------------------------------------------------- issue 13: silent inputs
    C("s1-well-posed-text", "stage 1", "well_posed_on_data given as text",
      "BacklashSetEstimator(0.05, well_posed_on_data='no').fit(u_ss, y_ss)",
      lambda: hb.BacklashSetEstimator(0.05, well_posed_on_data="no").fit(u_ss(), y_ss()),
      ParameterValidationError, "True or False"),
    C("s1-ustar-text", "stage 1", "PRBS level u* given as numeric text",
      "stage1.check_prbs_level('1.0')",
      lambda: stage1().check_prbs_level("1.0"),
      ParameterValidationError, "without quotes"),
    C("s1-margin-text", "stage 1", "margin given as numeric text",
      "stage1.suggest_prbs_level(margin='0.5')",
      lambda: stage1().suggest_prbs_level(margin="0.5"),
      ParameterValidationError, "without quotes"),
    C("s1-noise-bool", "stage 1", "output error bound given as a boolean",
      "BacklashSetEstimator(output_bound=True).fit(u_ss, y_ss)",
      lambda: hb.BacklashSetEstimator(True).fit(u_ss(), y_ss()),
      ParameterValidationError, "pass a number"),
    C("s1-contains-nan", "stage 1", "membership of a NaN parameter in a backlash set",
      "stage1.left_.contains([nan, 0.06])",
      lambda: stage1().left_.contains([np.nan, 0.06]),
      DataValidationError, "pass finite numbers"),
    C("s2-gain-bool", "stage 2", "steady-state gain given as a boolean",
      "LinearEIVSetEstimator(steady_state_gain=True, ...).fit(x, y)",
      lambda: lin(steady_state_gain=True).fit(x_inner(), y_prbs()),
      ParameterValidationError, "True is not taken as 1"),
    C("s2-noise-bool", "stage 2", "output error bound given as a boolean",
      "LinearEIVSetEstimator(output_bound=True, ...).fit(x, y)",
      lambda: lin(output_bound=True).fit(x_inner(), y_prbs()),
      ParameterValidationError, "pass a number"),
    C("s2-noise-two-columns", "stage 2", "per-sample output error bound with two columns",
      "LinearEIVSetEstimator(output_bound=np.full((N, 2), 0.05), ...).fit(x, y)",
      lambda: lin(output_bound=np.full((x_inner().size, 2), 0.05)).fit(x_inner(), y_prbs()),
      DataValidationError, "one value per sample"),
    C("s2-contains-nan", "stage 2", "membership of a NaN parameter vector",
      "stage2.contains([nan, 0.82, 2.15, -1.09])",
      lambda: stage2().contains([np.nan, 0.82, 2.15, -1.09]),
      DataValidationError, "pass finite numbers"),
    C("s2-zero-output", "stage 2", "an all-zero output record with a PRBS input",
      "LinearEIVSetEstimator(...).fit(x, np.zeros(N))",
      lambda: lin().fit(x_inner(), np.zeros(x_inner().size)),
      DataValidationError, "no information"),
    C("h-zero-output", "identifier", "an all-zero PRBS output",
      "HammersteinBacklashIdentifier(...).fit(u_prbs, np.zeros(N), steady_state=...)",
      lambda: hb.HammersteinBacklashIdentifier(hb.BacklashSetEstimator(0.05), lin()).fit(
          u_prbs(), np.zeros(u_prbs().size), steady_state=(u_ss(), y_ss())),
      DataValidationError, "no information"),
    C("h-contains-nan", "identifier", "membership of a NaN backlash parameter",
      "identifier.contains([0.25, nan, 0.26, 0.05], theta)",
      lambda: identified().contains([0.25, np.nan, 0.26, 0.05], [-0.76, 0.82, 2.15, -1.09]),
      DataValidationError, "pass finite numbers"),
    C("h-prbs-level-bool", "identifier", "prbs_level given as a boolean",
      "HammersteinBacklashIdentifier(bl, lin, prbs_level=True).fit(u_prbs, y_prbs, steady_state=...)",
      lambda: ident(prbs_level=True).fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "True is not taken as 1"),
    C("exp-prbs-level-numeric-text", "experiments", "PRBS level given as numeric text",
      "prbs_experiment(system, 50, '1.0', 0.05)",
      lambda: hb.prbs_experiment(SYS, 50, "1.0", 0.05),
      ParameterValidationError, "without quotes"),
    C("diag-noise-bool", "discrepancy", "output error bound given as a boolean",
      "diagnose(system, u_prbs, y_prbs, True)",
      lambda: _diagnose(SYS, u_prbs(), y_prbs(), True),
      ParameterValidationError, "True is not taken as 1"),
    C("diag-noise-text", "discrepancy", "output error bound given as numeric text",
      "diagnose(system, u_prbs, y_prbs, '0.05')",
      lambda: _diagnose(SYS, u_prbs(), y_prbs(), "0.05"),
      ParameterValidationError, "without quotes"),
    # ------------------------------------------------------------- issue 20: data scale
    C("s1-scale-huge", "stage 1", "data scaled by 1e300",
      "BacklashSetEstimator(0.05e300).fit(1e300 * u_ss, 1e300 * y_ss)",
      lambda: hb.BacklashSetEstimator(0.05e300).fit(1e300 * u_ss(), 1e300 * y_ss()),
      DataScaleError, "rescale"),
    C("s1-scale-tiny", "stage 1", "data scaled by 1e-300",
      "BacklashSetEstimator(0.05e-300).fit(1e-300 * u_ss, 1e-300 * y_ss)",
      lambda: hb.BacklashSetEstimator(0.05e-300).fit(1e-300 * u_ss(), 1e-300 * y_ss()),
      DataScaleError, "rescale"),
    C("s1-slope-tiny", "stage 1", "outputs 1e-9 times the inputs (slopes ~1e-10)",
      "BacklashSetEstimator(0.05e-6).fit(1e3 * u_ss, 1e-6 * y_ss)",
      lambda: hb.BacklashSetEstimator(0.05e-6).fit(1e3 * u_ss(), 1e-6 * y_ss()),
      DataScaleError, "slopes are too small"),
    C("s2-scale-huge", "stage 2", "data scaled by 1e300",
      "LinearEIVSetEstimator(output_bound=0.05e300, ...).fit(1e300 * x, 1e300 * y)",
      lambda: lin(output_bound=0.05e300).fit(1e300 * x_inner(), 1e300 * y_prbs()),
      DataScaleError, "leaves theta unchanged"),
    C("s2-scale-tiny", "stage 2", "data scaled by 1e-300",
      "LinearEIVSetEstimator(output_bound=0.05e-300, ...).fit(1e-300 * x, 1e-300 * y)",
      lambda: lin(output_bound=0.05e-300).fit(1e-300 * x_inner(), 1e-300 * y_prbs()),
      DataScaleError, "leaves theta unchanged"),
    C("h-scale-huge", "identifier", "PRBS data scaled by 1e300",
      "HammersteinBacklashIdentifier(bl, lin).fit(1e300 * u_prbs, 1e300 * y_prbs, steady_state=...)",
      lambda: ident().fit(
          1e300 * u_prbs(), 1e300 * y_prbs(), steady_state=(u_ss(), y_ss())),
      DataScaleError, "rescale"),
    C("diag-scale-tiny", "discrepancy", "data scaled by 1e-300",
      "diagnose(system, 1e-300 * u_prbs, 1e-300 * y_prbs, 0.05e-300)",
      lambda: _diagnose(SYS, 1e-300 * u_prbs(), 1e-300 * y_prbs(), 0.05e-300),
      DataScaleError, "rescale"),
    # ------------------------------------------------------------- chapter reproduction
    C("chapter-stage1", "chapter", "unknown stage-1 mode",
      "reproduce_chapter(stage1='table')",
      lambda: _chapter().reproduce_chapter("table", N=40, noise_levels=(0.05,), seeds=[0],
                                           method="lp"),
      ParameterValidationError, "stage1 must be one of"),
    C("chapter-level", "chapter", "noise level without a row in Table 22.1",
      "chapter_inner_bounds(0.1)",
      lambda: _chapter().chapter_inner_bounds(0.1),
      ParameterValidationError, "stage1='experiment'"),
    # ------------------------------------------------------------- own data (issue 14)
    C("eiv-nk-negative", "stage 2", "negative input delay",
      "LinearEIVSetEstimator(nk=-1, ...).fit(x, y)",
      lambda: lin(nk=-1).fit(x_inner(), y_prbs()),
      ParameterValidationError, "integer >= 0"),
    C("eiv-nk-and-b0", "stage 2", "the deprecated b0=True together with a delay nk > 0",
      "LinearEIVSetEstimator(nk=2, b0=True, ...).fit(x, y)",
      lambda: lin(nk=2, b0=True).fit(x_inner(), y_prbs()),
      ParameterValidationError, "pass only nk"),
    C("ident-gain-not-one", "identifier", "stage-2 estimator with a gain other than 1",
      "HammersteinBacklashIdentifier(bl, linear=LinearEIVSetEstimator(steady_state_gain=2))"
      ".fit(...)",
      lambda: ident(linear=lin(steady_state_gain=2.0)).fit(
          u_prbs(), y_prbs(), steady_state=(u_ss(), y_ss())),
      ParameterValidationError, "steady_state_gain=None"),
    C("iodata-kfold", "data", "non-consecutive samples of an IOData (KFold)",
      "IOData(u, y)[[0, 1, 5]]",
      lambda: hb.IOData(u_prbs(), y_prbs())[[0, 1, 5]],
      DataValidationError, "TimeSeriesSplit"),
    C("iodata-time-irregular", "data", "time column not uniformly sampled",
      "IOData.from_csv('<tmp>/t.csv')",
      lambda: hb.IOData.from_csv(csv_file("t.csv", "t,u,y\n0,1,2\n1,1,2\n3,1,2\n")),
      DataValidationError, "Resample"),
    C("iodata-dt-mismatch", "data", "time column disagrees with dt",
      "IOData.from_csv('<tmp>/t2.csv', dt=0.1)",
      lambda: hb.IOData.from_csv(csv_file("t2.csv", "t,u,y\n0,1,2\n0.5,1,2\n1,1,2\n"),
                                 dt=0.1),
      DataValidationError, "drop one of them"),
    C("eiv-fit-iodata-and-y", "stage 2", "an IOData and another y",
      "LinearEIVSetEstimator(...).fit(IOData(u, y), y2)",
      lambda: lin().fit(hb.IOData(x_inner(), y_prbs()), y_prbs() + 1.0),
      DataValidationError, "without y"),
    C("s2-relaxation-basis", "stage 2", "unknown moment basis",
      "LinearEIVSetEstimator(method='moment', relaxation_basis='dense', ...).fit(x, y)",
      lambda: lin(method="moment", relaxation_basis="dense").fit(x_inner(), y_prbs()),
      ParameterValidationError, "'sparse' or 'full'"),
    C("s2-relaxation-max-work", "stage 2", "moment size budget not a positive number",
      "LinearEIVSetEstimator(method='moment', relaxation_max_work=0, ...).fit(x, y)",
      lambda: lin(method="moment", relaxation_max_work=0).fit(x_inner(), y_prbs()),
      ParameterValidationError, "relaxation_max_work must be a number > 0"),
    C("diag-signal-row", "discrepancy", "input given as a row (1, N)",
      "diagnose(system, u_prbs[None, :], y_prbs, 0.05)",
      lambda: _diagnose(SYS, u_prbs()[None, :], y_prbs(), 0.05),
      DataValidationError, "shape (N,) or (N, 1)"),
    C("noise-wrong-length", "experiments", "per-sample output error bound of the wrong length",
      "uniform_noise(5, [0.1, 0.2])",
      lambda: __import__("hammerbound.systems.experiments", fromlist=["x"]).uniform_noise(
          5, [0.1, 0.2]),
      DataValidationError, "one value per sample"),
    C("backlash-sim-text", "systems", "text input to the backlash simulation",
      "simulate_backlash(['a', 'b'], 1, 0.1, 1, 0.1)",
      lambda: hb.simulate_backlash(["a", "b"], 1.0, 0.1, 1.0, 0.1),
      DataValidationError, "real numbers"),
]


def _check_output(path, force=False):
    from hammerbound.app.paths import check_output_file

    return check_output_file(path, force=force)


def _check_report_dir():
    from hammerbound.app.paths import check_output_dir
    from hammerbound.app.report import REPORT_FILES

    (CSV_DIR / "report-dir").mkdir(parents=True, exist_ok=True)
    csv_file("report-dir/report.md", "# earlier report\n")
    return check_output_dir(CSV_DIR / "report-dir", REPORT_FILES)


def _chapter():
    import hammerbound.app.chapter as chapter

    return chapter


#: The machine memory the cases run with (the moment method's size guard also refuses what
#: the machine cannot hold): docs/errors.md is then the same on every machine. The test
#: suite fixes the same value for every test (tests/conftest.py).
MACHINE_MEMORY = 64.0 * 2**30


def run_case(case: ErrorCase) -> BaseException | None:
    """Run one case (with :data:`MACHINE_MEMORY`); return the exception it raised (None if
    it did not raise)."""
    from unittest import mock

    from hammerbound.relaxations.moment import size

    with mock.patch.object(size, "physical_memory", lambda: MACHINE_MEMORY):
        try:
            case.func()
        except Exception as exc:  # noqa: BLE001 - we report whatever is raised
            return exc
    return None
