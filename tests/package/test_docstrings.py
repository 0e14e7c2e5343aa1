"""Every argument of the public API is documented in its numpydoc docstring."""

from __future__ import annotations

import inspect
import re

import pytest

import hammerbound as hb
from hammerbound.discrepancy import diagnose
from hammerbound.relaxations.exact.bnb import exact_bounds
from hammerbound.relaxations.lp import lp_bounds
from hammerbound.relaxations.moment.relaxation import moment_bounds

ESTIMATORS = [hb.BacklashSetEstimator, hb.LinearEIVSetEstimator, hb.HammersteinBacklashIdentifier,
              hb.OrderSelectionCV]
FUNCTIONS = [lp_bounds, moment_bounds, exact_bounds, diagnose,
             hb.LinearEIVSetEstimator.fit, hb.HammersteinBacklashIdentifier.fit,
             hb.eiv_example, hb.relaxations.consistency]


def _documented(doc: str) -> set[str]:
    names = set()
    for line in doc.splitlines():
        m = re.match(r"^\s{0,8}([A-Za-z_][\w, ]*?)\s*:\s", line)
        if m:
            names.update(n.strip() for n in m.group(1).split(","))
    return names


@pytest.mark.parametrize("obj", ESTIMATORS + FUNCTIONS, ids=lambda o: o.__qualname__)
def test_every_argument_is_documented(obj):
    target = obj.__init__ if inspect.isclass(obj) else obj
    params = [p for p in inspect.signature(target).parameters if p not in ("self",)]
    params = [p for p in params if not p.startswith("_")]
    doc = inspect.getdoc(obj) or ""
    if inspect.isclass(obj):
        doc += "\n" + (inspect.getdoc(obj.__init__) or "")
    missing = [p for p in params if p not in _documented(doc)
               and f"``{p}``" not in doc and f"`{p}`" not in doc]
    assert not missing, f"{obj.__qualname__}: undocumented argument(s) {missing}"
