"""The test suite's fixtures (the third-party data under ../shared/data/) and its two tiers.

Layout
------
One folder per layer of the package (``docs/architecture.md``): ``base/`` (data, systems,
solvers, results), ``relaxations/``, ``modelset/``, ``stage1/``, ``stage2/``, ``joint/``,
``hammerstein/`` (the identifier, order selection, reliability), ``discrepancy/``, ``app/``
(command line, chapter, report, docs, error table) and ``package/`` (layout, docstrings,
vocabulary). Test file names are unique across the folders. What the tests check the
package against -- our own play operator, simulators and feasibility LPs, none importing
hammerbound -- is in ``tests/oracles.py``; the catalogue of malformed inputs is
``tests/error_cases.py``. Test modules import from these two only, never from each other
or from this file (``pyproject.toml`` puts ``tests/`` on the import path).

Two tiers
---------
``python -m pytest -q tests`` (the README's command) runs the **quick tier**: every test
not marked ``deep``, about 4 minutes on a 2-core machine. ``python -m pytest -q -m deep
tests`` runs the **deep tier**; ``.ci/run`` runs both, the quick one first. ``pyproject.toml``
deselects ``deep`` by default (``addopts = ... -m "not deep"``; a later ``-m`` on the
command line wins, e.g. ``-m "deep or not deep"`` for everything) and runs one
pytest-xdist worker per core with each test file on one worker (``-n auto --dist
loadfile``; ``-n0``: one process, e.g. for ``--pdb``).

Deep are:

* the extremal-noise sweeps and other long tests, marked ``@pytest.mark.deep`` where they
  are defined (``@pytest.mark.slow``, its former name, still counts as deep);
* the soundness Monte Carlo suites (every hypothesis ``@given`` test);
* the cases listed in :data:`DEEP` below, each with its reason: the costly variants of a
  test whose cheap variants stay quick, and tests whose guard a quick test shares.

What stays quick: at least one case of every guarantee (each method with noise exactly at
the bound, stage 1, the identifier, certified solver fallbacks), the docs, the CLI in
process and one subprocess check of each program's stdout, scikit-learn's estimator checks.
Per-test costs: ``python -m pytest --durations=0`` (see the CHANGELOG for the measured
split).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

#: the deep tier's cases (see the module docstring): pattern (``*`` matches any text) of the
#: node id from the test file's name on (``test_x.py::...``, whatever its folder), and why
#: the case can wait for the deep tier
DEEP = {
    "test_cli_subprocess.py::test_demo_*":
        "the whole demo in a fresh interpreter, 7-9 s each (test_cli.py and test_chapter.py "
        "run the demo in process)",
    "test_cli_subprocess.py::test_identify_json_stdout_is_only_json":
        "6 s; test_cli_eiv.py's subprocess check guards stdout, test_cli.py::test_identify_"
        "json_and_report the identify JSON",
    "test_cli_subprocess.py::test_version_is_the_distribution_version":
        "a fresh interpreter; test_owndata.py::test_version_agrees_with_distribution",
    "test_cli_subprocess.py::test_eiv_json_stdout_is_only_json":
        "same guard as test_cli_eiv.py::test_eiv_json_subprocess_stdout_is_only_json",
    "test_cli_subprocess.py::test_identify_report_*":
        "report overwrite guards through a subprocess (test_cli.py checks them in process)",
    "test_cli_subprocess.py::test_diagnose_plot_checked_and_force":
        "plot overwrite guard through a subprocess, 5 s",
    "test_cli_subprocess.py::test_benchmark_output_checked_before_the_run":
        "benchmark output guard through a subprocess (test_cli.py::test_benchmark_quick)",
    "test_reliability.py::test_inexact_solver_never_too_tight[*-cvxopt-*]":
        "the cvxopt variants, 1.5-4 s each (the Clarabel variants stay quick)",
    "test_moment.py::test_crippled_solver_never_reports_a_too_tight_bound[cvxopt-*]":
        "the cvxopt variants, 3-5 s each (the Clarabel variants stay quick)",
    "test_reliability.py::test_pickle_round_trip_and_determinism[linear-exact]":
        "5 s; the identifier with the exact method stays quick",
    "test_uncertainty_weight.py::test_a_higher_order_is_never_worse[second-*]":
        "the first-order case stays quick",
    "test_uncertainty_weight.py::test_issue_cases_through_a_csv_file":
        "the same case as test_issue_cases_give_a_certified_weight, read from a CSV file",
    "test_layout.py::test_old_module_paths_warn_and_work[backlash-*]":
        "a fresh interpreter per old path; [eiv-...] stays quick",
    "test_layout.py::test_old_module_paths_warn_and_work[experiments-*]":
        "a fresh interpreter per old path; [eiv-...] stays quick",
    "test_layout.py::test_old_module_paths_warn_and_work[iodata-*]":
        "a fresh interpreter per old path; [eiv-...] stays quick",
    "test_discrepancy_boundary.py::test_cli_exits_0_on_a_correct_model_with_noise_at_the_"
    "bound[extra_pole]": "3.5 s; [backlash] stays quick",
    "test_hammerstein.py::test_moment_order1_on_chapter_example[0.3]":
        "[0.02] stays quick",
    "test_discrepancy.py::test_names_hidden_effect_and_closes_gap[*-1]":
        "the second seed of each effect (the first stays quick)",
    "test_moment.py::test_order1_contains_truth_and_every_verified_point[1-0.05-False]":
        "Delta eta = 0.005 and 0.05 (two-level) stay quick",
    "test_moment.py::test_order1_contains_truth_and_every_verified_point[2-0.2-False]":
        "Delta eta = 0.005 and 0.05 (two-level) stay quick",
    "test_order_selection.py::test_picks_the_true_order_and_never_a_falsified_one[1-at_bound]":
        "3-5 s; the second-order at-bound case and the issue's record stay quick",
    "test_order_selection.py::test_picks_the_true_order_and_never_a_falsified_one[2-uniform]":
        "the issue's second-order record (uniform errors) stays quick",
    "test_moment_ends.py::test_estimator_moment_ends_are_labelled_by_their_source[uniform]":
        "12 s of order-1 moment at N = 150; [at_bound] (the case that failed before the fix) "
        "stays quick",
    "test_exact.py::test_n_jobs_two_matches_serial":
        "joblib parity, also guarded by test_reliability.py::test_parallel_and_serial_agree",
    "test_working_set.py::test_automatic_working_set_only_for_independent_input_errors":
        "the automatic choice is a speed heuristic (the bounds are certified either way)",
    "test_stage2_limits.py::test_time_limited_exact_keeps_the_lp_bound[default]":
        "[None] stays quick",
    "test_stage2_limits.py::test_total_budget_shared_by_parallel_workers":
        "the budget with 2 workers; the serial budget tests stay quick",
    **{f"test_boundary_stage2.py::test_lp_extremal_noise[{a}-{a + 24}]":
       "extremal-noise sweep; its first chunk [0-24] stays quick" for a in range(25, 300, 25)},
}


def _by_file_name(nodeid: str) -> str:
    """``test_x.py::test_y[...]`` of a node id in any folder of tests/ (file names are
    unique across the folders)."""
    path, sep, rest = nodeid.partition("::")
    return Path(path).name + sep + rest


def _deep_reason(nodeid: str):
    import fnmatch

    rel = _by_file_name(nodeid)
    for pattern, reason in DEEP.items():
        if fnmatch.fnmatchcase(rel, pattern.replace("[", "[[]")):
            return pattern, reason
    return None, None


@pytest.hookimpl(tryfirst=True)  # before -m deselects by marker
def pytest_collection_modifyitems(config, items):
    """Mark the deep tier (see the module docstring); a pattern of :data:`DEEP` whose file
    was collected but that matches no test is an error (a renamed test)."""
    used, files = set(), set()
    for item in items:
        files.add(_by_file_name(item.nodeid).split("::")[0])
        pattern, _ = _deep_reason(item.nodeid)
        if pattern is not None:
            used.add(pattern)
        if (pattern is not None or item.get_closest_marker("slow") is not None
                or getattr(getattr(item, "obj", None), "is_hypothesis_test", False)):
            item.add_marker(pytest.mark.deep)
    stale = [p for p in DEEP if p.split("::")[0] in files and p not in used]
    if stale:
        raise pytest.UsageError("tests/conftest.py DEEP names no collected test: "
                                + ", ".join(stale))


#: test and benchmark data that are not the project's (read in place, never copied into it)
SHARED_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def _shared_data(*parts) -> Path:
    path = SHARED_DATA.joinpath(*parts)
    if not path.is_file():
        pytest.skip(f"third-party data not found at {path} (tests read it from "
                    "../shared/data/ beside the repository; it is not part of the package)")
    return path


@pytest.fixture(scope="session")
def shared_data():
    """``shared_data(*parts)``: the path of a file under ``../shared/data/`` (relative to the
    repository root); the calling test is skipped, with the path in the reason, when the
    file is not there."""
    return _shared_data


@pytest.fixture(scope="session")
def lric_record(shared_data):
    """``(u, y)`` of the LRIC exam record (P0li22/LRIC, 22 February 2017: 30 samples,
    dt = 0.1, input and output errors bounded by 0.05), or skip."""
    d = np.genfromtxt(shared_data("lric", "eiv_first_order_2017.csv"), delimiter=",",
                      names=True)
    return d["u"], d["y"]


@pytest.fixture(autouse=True)
def _fixed_machine_memory(monkeypatch):
    """Every test sees the same machine memory (``moment.size.physical_memory``,
    ``error_cases.MACHINE_MEMORY``): the moment method's size guard also refuses what the
    machine cannot hold, so its messages would otherwise depend on the machine. Tests of
    the memory refusal set their own value; the real function is tested on its own."""
    from error_cases import MACHINE_MEMORY

    from hammerbound.relaxations.moment import size

    monkeypatch.setattr(size, "physical_memory", lambda: MACHINE_MEMORY)
