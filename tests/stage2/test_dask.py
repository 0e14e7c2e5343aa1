"""Issue 18, item 3: the 2 p interval ends run on a Dask cluster through joblib's Dask
backend, unchanged (no home-made scheduler).

A real ``LocalCluster`` with worker *processes* is started, so the tasks are pickled and
shipped as they would be to a remote cluster; the task stream proves that they ran there.
"""

from __future__ import annotations

import joblib
import numpy as np
import pytest

distributed = pytest.importorskip("distributed", reason="install hammerbound[test] (dask[distributed])")
from dask.distributed import Client, LocalCluster, get_task_stream  # noqa: E402

from hammerbound import (  # noqa: E402
    BacklashSetEstimator,
    HammersteinBacklashIdentifier,
    LinearEIVSetEstimator,
    chapter_example,
)


def _identifier(deta, method, n_jobs):
    return HammersteinBacklashIdentifier(
        BacklashSetEstimator(deta),
        LinearEIVSetEstimator(output_bound=deta, method=method, n_jobs=n_jobs))


@pytest.fixture(scope="module")
def client():
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as c:
        yield c


@pytest.mark.deep
def test_identifier_bounds_on_a_local_cluster(client):
    deta, method = 0.05, "exact"
    ex = chapter_example(deta, N=100, random_state=1)
    # the same job split on local worker processes (loky), for an identical reference
    local = _identifier(deta, method, 2).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    with get_task_stream(client) as ts, joblib.parallel_config(backend="dask"):
        remote = _identifier(deta, method, 2).fit(ex.prbs.u, ex.prbs.y, steady_state=ex.steady)
    # the bound problems really went to the cluster's workers ...
    workers = {t["worker"] for t in ts.data}
    assert len(ts.data) >= 2, ts.data
    assert workers <= set(client.scheduler_info()["workers"])
    # ... and gave the same certified intervals as the local run, with the truth inside
    np.testing.assert_allclose(remote.bounds_, local.bounds_, rtol=0, atol=1e-9)
    assert remote.contains(ex.gamma_true, ex.theta_true)
    assert all(i.status == "optimal" for i in remote.linear_.result_.infos)
