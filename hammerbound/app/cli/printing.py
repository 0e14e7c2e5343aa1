"""Text and JSON pieces that ``eiv`` and ``identify`` print alike: the record, the
assumptions the bounds rest on, the central transfer function."""

from __future__ import annotations

import json

import numpy as np

from ...tables import dt_text, poly_z

__all__ = ["assumption_lines", "data_fields", "dt_text", "poly_z", "record_line",
           "transfer_function"]


def transfer_function(linear, dt):
    """``(text line, JSON record)`` of the central model of a fitted stage-2 estimator."""
    tf = linear.to_transfer_function()
    num = np.ravel(tf.num[0][0]).tolist()
    den = np.ravel(tf.den[0][0]).tolist()
    unit = getattr(linear, "time_unit_", "")
    text = (f"central model: G(z) = ({poly_z(num)}) / ({poly_z(den)}), "
            f"dt = {dt_text(dt, unit)}")
    return text, {"num": num, "den": den, "dt": dt, "time_unit": unit, "variable": "z"}


def data_fields(data) -> dict:
    """The record's fields of a JSON output: ``N``, ``dt`` and its ``time_unit``, the
    ``input`` and ``output`` names and their units (empty when not known)."""
    return {"N": data.N, "dt": data.dt, "time_unit": data.time_unit,
            "input": data.input_name, "output": data.output_name,
            "input_unit": data.input_unit, "output_unit": data.output_unit}


def record_line(path, data) -> str:
    """``data.csv: N = 60, dt = 0.1, input 'u', output 'y'`` (``input 'u' [V]`` with a
    unit: the column ``u [V]``)."""
    return (f"{path}: N = {data.N}, dt = {dt_text(data.dt, data.time_unit)}, "
            f"input {data.signal_text('input')}, output {data.signal_text('output')}")


def assumption_lines(given, assumed) -> list[str]:
    """``given: ...`` and ``assumed: ...`` lines (what the bounds rest on)."""
    out = ["given: " + "; ".join(given)] if given else []
    return out + [f"assumed: {a}" for a in assumed]


def json_text(obj) -> str:
    """``obj`` as strict JSON (RFC 8259): every non-finite number (an interval end the data
    do not bound) is ``null``; anything else non-finite raises instead of printing
    ``Infinity`` or ``NaN``, which JSON parsers reject."""
    from ...results.base import jsonable

    return json.dumps(jsonable(obj), indent=2, allow_nan=False)
