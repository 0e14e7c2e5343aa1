"""scikit-learn's estimator checks on the stage-2 estimator and the identifier (issue 29,
item 14; the stage-1 estimator's are in test_backlash.py). Every check that fails does so
by design, for the reason given; the others pass.

The stage-2 estimator is checked with an output bound that any of the checks' random data
satisfy and a finite a priori box (so that the set is never empty nor unbounded): then the
checks exercise the scikit-learn API (cloning, pickling, idempotent fits, ``n_features_in_``,
pipelines). With a realistic bound, random data falsify the model and fit raises
``EmptyFeasibleSetError``: that is the estimator's purpose, not an API fault.
"""

from __future__ import annotations

from sklearn.utils.estimator_checks import parametrize_with_checks

import hammerbound as hb

# the estimators take one signal: their input tag one_d_array makes the checks pass 1-D X,
# which these checks then index as a 2-D array (IndexError inside scikit-learn's check)
ONE_D = "the check indexes 1-D X (one signal, tag one_d_array) as a 2-D array"
ONE_SIGNAL_DATA = "the check's data have several columns: one input signal only"
OWN_MESSAGES = {
    "check_complex_data": "typed DataValidationError with hammerbound's own message "
                          "(real numbers needed), not scikit-learn's wording",
    "check_dtype_object": "object arrays are refused with a message to convert them, not cast",
    "check_estimators_empty_data_messages": "typed DataValidationError with hammerbound's own "
                                            "message (a 1-D signal of N samples needed)",
    "check_estimators_nan_inf": ONE_SIGNAL_DATA + " (NaN and inf are refused: test_validation)",
    "check_estimator_sparse_array": "the check cannot build a 1-D sparse array",
    "check_fit1d": "1-D X is the input signal, by design",
    "check_supervised_y_2d": "y of shape (N, 1) is the output signal: accepted without warning",
}
COMMON = {
    **{c: ONE_D for c in (
        "check_dont_overwrite_parameters", "check_f_contiguous_array_estimator",
        "check_regressors_no_decision_function", "check_methods_sample_order_invariance",
        "check_methods_subset_invariance", "check_fit2d_1sample", "check_fit2d_1feature",
        "check_dict_unchanged", "check_fit2d_predict1d", "check_n_features_in",
        "check_n_features_in_after_fitting")},
    **OWN_MESSAGES,
}
LINEAR_EXPECTED_FAILED = {
    **COMMON,
    "check_regressors_train": "random data with a bound of 1e3: the central model of so wide "
                              "a set does not predict them (R^2 < 0.5)",
    "check_regressors_train(readonly_memmap=True)": "as check_regressors_train",
    "check_regressors_train(readonly_memmap=True,X_dtype=float32)": "as check_regressors_train",
}
NEEDS_STEADY = "fit needs the steady-state record of stage 1 (steady_state=...), which "\
               "scikit-learn's checks do not pass"
IDENTIFIER_EXPECTED_FAILED = {
    **COMMON,
    **{c: NEEDS_STEADY for c in (
        "check_fit_score_takes_y", "check_estimators_overwrite_params",
        "check_estimators_fit_returns_self", "check_readonly_memmap_input",
        "check_positive_only_tag_during_fit", "check_estimators_dtypes",
        "check_pipeline_consistency", "check_estimators_pickle",
        "check_estimators_pickle(readonly_memmap=True)", "check_regressors_train",
        "check_regressors_train(readonly_memmap=True)",
        "check_regressors_train(readonly_memmap=True,X_dtype=float32)",
        "check_regressor_data_not_an_array", "check_supervised_y_2d", "check_regressors_int",
        "check_fit_idempotent", "check_fit_check_is_fitted")},
}
del IDENTIFIER_EXPECTED_FAILED["check_fit1d"]  # the identifier refuses fit without stage 1


def _expected(est):
    return (IDENTIFIER_EXPECTED_FAILED if isinstance(est, hb.HammersteinBacklashIdentifier)
            else LINEAR_EXPECTED_FAILED)


@parametrize_with_checks(
    [hb.LinearEIVSetEstimator(1, 1, output_bound=1e3, method="lp",
                              theta_box=[[-1.0, 1.0], [-10.0, 10.0]]),
     # the two-stage procedure: scikit-learn's random data as one record would be a long
     # search of a set that is empty or unbounded (the one-record API: test_one_record*.py)
     hb.HammersteinBacklashIdentifier(hb.BacklashSetEstimator(0.05),
                                      hb.LinearEIVSetEstimator(output_bound=0.05, method="lp"),
                                      procedure="two-stage")],
    expected_failed_checks=_expected)
def test_sklearn_estimator_checks(estimator, check):
    check(estimator)
