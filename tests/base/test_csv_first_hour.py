"""CSV files as a new user has them (new-user trial): Excel's UTF-8 with a byte-order
mark, tab-separated files with the tab typed as \\t, decimal commas, no header row, a
directory instead of a file."""

from __future__ import annotations

import numpy as np
import pytest

import hammerbound as hb
from hammerbound.app.cli import main
from hammerbound.exceptions import DataValidationError

U = np.array([0.5, -0.25, 1.0, 0.75, -1.0, 0.125])
Y = np.array([0.0, 0.25, -0.125, 0.5, 0.375, -0.5])


def _write(tmp_path, text, name="rec.csv", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


def _rows(sep=",", dec="."):
    return "".join(f"{0.1 * k:.1f}{sep}{str(u).replace('.', dec)}{sep}"
                   f"{str(y).replace('.', dec)}\n" for k, (u, y) in enumerate(zip(U, Y, strict=True)))


@pytest.mark.parametrize("header", ["u,y", "t,u,y"])
def test_byte_order_mark_is_read(tmp_path, header):
    body = "".join(f"{u},{y}\n" for u, y in zip(U, Y, strict=True)) if header == "u,y" else _rows()
    path = _write(tmp_path, header + "\n" + body, encoding="utf-8-sig")
    data = hb.IOData.from_csv(path)
    assert np.array_equal(data.u, U) and np.array_equal(data.y, Y)
    if header == "t,u,y":
        assert data.dt == pytest.approx(0.1)


@pytest.mark.parametrize("spelling", ["\\t", "tab", "\t"])
def test_tab_spellings(tmp_path, spelling):
    path = _write(tmp_path, "t\tu\ty\n" + _rows("\t"), "rec.tsv")
    data = hb.IOData.from_csv(path, delimiter=spelling)
    assert np.array_equal(data.u, U)


@pytest.mark.parametrize("sep, said", [("\t", "tab"), (";", "';'")])
def test_the_separator_is_guessed_in_the_hint(tmp_path, capsys, sep, said):
    path = _write(tmp_path, f"t{sep}u{sep}y\n" + _rows(sep))
    rc = main(["eiv", str(path), "--na", "1", "--nb", "1", "--output-bound", "0.1",
               "--method", "lp"])
    err = capsys.readouterr().err
    assert rc == 2 and f"seems separated by {said}; pass --delimiter {said}" in err


def test_decimal_comma_and_missing_header_and_directory(tmp_path):
    path = _write(tmp_path, "t;u;y\n" + _rows(";", ","))
    with pytest.raises(DataValidationError, match="Decimal commas are not read"):
        hb.IOData.from_csv(path, delimiter=";")
    path = _write(tmp_path, _rows(), "nohead.csv")
    with pytest.raises(DataValidationError, match="seems to have no header row"):
        hb.IOData.from_csv(path)
    with pytest.raises(DataValidationError, match="is a directory, not a CSV file"):
        hb.IOData.from_csv(tmp_path)


def test_a_table_of_both_signals_as_x_gets_advice():
    """A DataFrame holding the input and the output passed as X alone (trial 9): the error
    names its columns and the two ways to pass them."""
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(0)
    frame = pd.DataFrame({"valve": rng.uniform(-1, 1, 50), "flow": rng.uniform(-1, 1, 50)})
    est = hb.LinearEIVSetEstimator(output_bound=0.1, method="lp")
    with pytest.raises(hb.exceptions.DataValidationError,
                       match=r"2 columns \(valve, flow\).*IOData\.from_frame\(frame, "
                             r"u='<input column>'"):
        est.fit(frame)
    with pytest.raises(hb.exceptions.DataValidationError, match="2 columns: the model"):
        est.fit(frame.to_numpy())
