"""Tests of the vessel log format (hybridship.logs.io) and log preprocessing."""

from __future__ import annotations

import gzip
import json
import os
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from hybridship import frames
from hybridship.logs import (
    LogFormatError,
    LogFormatWarning,
    derivative_by_segment,
    filtered_derivative,
    log_to_arrays,
    moving_average_start,
    read_log,
    segmentwise,
    split_segments,
    validate_log,
    write_log,
)
from hybridship.logs.io import heading_looks_like_radians

THRUSTERS = ["tunnel", "port", "stbd"]
ROTATABLE = [False, True, True]

# Circular track: constant body velocity and yaw rate.
U_M_S, V_M_S, R_DEG_S = 2.0, 0.5, 1.0


def circle_log(n: int = 120, dt_s: float = 1.0, *, velocities: bool = True) -> pd.DataFrame:
    """A synthetic, format-conforming log of a vessel on a circle (analytic positions)."""
    t = np.arange(n) * dt_s
    w = np.radians(R_DEG_S)
    psi = np.radians(340.0) + w * t  # crosses north, so the logged heading wraps
    north = (U_M_S * np.sin(psi) + V_M_S * np.cos(psi)) / w
    east = (-U_M_S * np.cos(psi) + V_M_S * np.sin(psi)) / w
    df = pd.DataFrame(
        {
            "time_s": t,
            "north_m": north,
            "east_m": east,
            "heading_deg": np.degrees(frames.wrap_2pi(psi)),
            "wind_speed_m_s": 8.0 + 0.01 * t,
            "wind_dir_deg": np.full(n, 45.0),
            "tunnel_rpm": np.linspace(-100.0, 100.0, n),
            "port_rpm": np.full(n, 120.0),
            "port_azimuth_deg": np.full(n, -30.0),
            "stbd_rpm": np.full(n, 110.0),
            "stbd_azimuth_deg": np.full(n, 30.0),
            "dp_active": (t < t[n // 2]).astype(int),
            "truth_current_speed_mps": np.full(n, 0.2),
        }
    )
    if velocities:
        df.insert(4, "u_m_s", np.full(n, U_M_S))
        df.insert(5, "v_m_s", np.full(n, V_M_S))
        df.insert(6, "r_deg_s", np.full(n, R_DEG_S))
    return df


# --------------------------------------------------------------------------------------
# Round trip and atomic writes
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["log.csv", "log.csv.gz", "log.parquet"])
def test_round_trip(tmp_path, name):
    df = circle_log()
    before = df.copy(deep=True)
    path = tmp_path / name
    write_log(df, path, channel_names=THRUSTERS, rotatable=ROTATABLE)
    back = read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)
    pd.testing.assert_frame_equal(back, df, check_exact=True)
    pd.testing.assert_frame_equal(df, before, check_exact=True)  # input untouched
    assert sorted(os.listdir(tmp_path)) == [name]  # no temp file left behind


def test_csv_gz_is_gzip_and_reproducible(tmp_path):
    df = circle_log()
    write_log(df, tmp_path / "a.csv.gz")
    write_log(df, tmp_path / "b.csv.gz")
    a, b = (tmp_path / "a.csv.gz").read_bytes(), (tmp_path / "b.csv.gz").read_bytes()
    assert a[:2] == b"\x1f\x8b" and a == b


def test_write_replaces_existing_file_only_on_success(tmp_path, monkeypatch):
    path = tmp_path / "log.csv"
    first, second = circle_log(50), circle_log(60)
    write_log(first, path)
    write_log(second, path)  # success: replaced
    pd.testing.assert_frame_equal(read_log(path), second)
    good_bytes = path.read_bytes()

    bad = second.copy()
    bad.loc[3, "north_m"] = np.nan
    with pytest.raises(LogFormatError, match="north_m"):
        write_log(bad, path)
    assert path.read_bytes() == good_bytes

    def fail_midway(self, buf, *args, **kwargs):
        buf.write(b"time_s,north_m\n0.0,")  # partial output, then a crash
        raise OSError("disk full")

    monkeypatch.setattr(pd.DataFrame, "to_csv", fail_midway)
    with pytest.raises(OSError, match="disk full"):
        write_log(second, path)
    assert path.read_bytes() == good_bytes
    assert sorted(os.listdir(tmp_path)) == ["log.csv"]


def test_read_only_files_and_folders_are_not_replaced(tmp_path):
    """Every output goes through one atomic write: it refuses a read-only file (a rename
    would replace it anyway) and a folder, and leaves both as they were."""
    import stat

    from hybridship.fileio import atomic_write

    kept = tmp_path / "kept.csv"
    kept.write_bytes(b"precious")
    kept.chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)
    with pytest.raises(PermissionError, match="kept.csv: is read-only"):
        atomic_write(kept, lambda fh: fh.write(b"new"))
    assert kept.read_bytes() == b"precious"
    with pytest.raises(IsADirectoryError, match="is a directory"):
        atomic_write(tmp_path, lambda fh: fh.write(b"new"))
    assert sorted(x.name for x in tmp_path.iterdir()) == ["kept.csv"]



def test_file_writers_refuse_what_is_not_a_path_or_bytes_before_writing(tmp_path, monkeypatch):
    """Before: os' "expected str, bytes or os.PathLike object", an empty path read as the current
    folder, an AttributeError for bytes given as text, a folder made before a str content
    failed in the writer, and a lone input path read as files named by its characters."""
    from hybridship.fileio import atomic_write, record_inputs, write_output_files, write_text

    monkeypatch.chdir(tmp_path)
    for bad, err, match in ((None, TypeError, "path: expected a file path"), (3, TypeError, "path: expected a file path"),
                            ("", ValueError, "path: expected a file path, got an empty one")):
        with pytest.raises(err, match=match):
            atomic_write(bad, lambda fh: fh.write(b"x"))
    with pytest.raises(TypeError, match="write: expected a function"):
        atomic_write("a.txt", b"x")
    for bad in (b"x", None):
        with pytest.raises(TypeError, match="text: expected a str"):
            write_text("a.txt", bad)
    with pytest.raises(TypeError, match="contents: expected file name -> bytes, got 'b.csv' -> str"):
        write_output_files("out", {"a.csv": b"1", "b.csv": "2"})
    with pytest.raises(TypeError, match="contents: expected a dict"):
        write_output_files("out", ["a.csv"])
    (tmp_path / "in.csv").write_bytes(b"1")
    with pytest.raises(TypeError, match="inputs: expected a list of file paths, got the single path"):
        record_inputs("o.md", "in.csv")
    with pytest.raises(FileNotFoundError, match="inputs: not a file: nope.csv"):
        record_inputs("o.md", ["in.csv", "nope.csv"])
    assert sorted(x.name for x in tmp_path.iterdir()) == ["in.csv"]      # nothing written, no folder made
    assert write_text("a.txt", "ok").read_text() == "ok"

def test_output_files_are_not_written_where_a_folder_of_that_name_is(tmp_path):
    """A folder at one of the names was found only when that file was written: the files
    before it were written and left out of the folder's record (so refused by the next run)."""
    from hybridship.fileio import check_output_files, write_output_files

    (tmp_path / "b.csv").mkdir()
    with pytest.raises(FileExistsError, match=r"b\.csv: is a folder, where the file b\.csv would be written"):
        check_output_files(tmp_path, ["a.csv", "b.csv"])
    with pytest.raises(FileExistsError, match=r"b\.csv: is a folder"):
        write_output_files(tmp_path, {"a.csv": b"1", "b.csv": b"2"})
    assert sorted(x.name for x in tmp_path.iterdir()) == ["b.csv"]      # nothing written
    check_output_files(tmp_path, ["a.csv"], removed=["b.csv"])      # a folder is never removed: no error
    assert write_output_files(tmp_path, {"a.csv": b"1"}, stale=["b.csv"])["a.csv"].read_bytes() == b"1"
    assert (tmp_path / "b.csv").is_dir()


def test_stale_output_files_given_as_a_generator_are_removed(tmp_path):
    """``stale`` was read once by the check: given as a generator, the removal found it empty and
    an earlier run's figure stayed beside the new tables, still in the folder's record."""
    from hybridship.fileio import OUTPUTS_RECORD, write_output_files

    write_output_files(tmp_path, {"a.csv": b"1", "fig.png": b"x"})
    write_output_files(tmp_path, {"a.csv": b"2"}, stale=(name for name in ["fig.png"]))
    assert sorted(x.name for x in tmp_path.iterdir()) == [OUTPUTS_RECORD, "a.csv"]
    assert json.loads((tmp_path / OUTPUTS_RECORD).read_text()) == ["a.csv"]


def test_a_file_both_written_and_stale_is_refused_before_writing(tmp_path):
    """It was written, then removed as stale, and its (missing) path returned."""
    from hybridship.fileio import write_output_files

    with pytest.raises(ValueError, match=r"^stale: fig\.png also in contents"):
        write_output_files(tmp_path / "out", {"a.csv": b"1", "fig.png": b"x"}, stale=["fig.png"])
    assert not (tmp_path / "out").exists()


def test_output_files_written_before_a_failure_are_replaced_by_the_next_run(tmp_path, monkeypatch):
    """The record of outputs was written after the last file: files written before a failure
    (a full disk, an interrupt) were left out of it, and the next run refused them as files
    hybridship did not write."""
    import errno

    from hybridship import fileio

    real = fileio.atomic_write

    def full_disk_at_b(path, write):
        if Path(path).name == "b.csv":
            raise OSError(errno.ENOSPC, f"{path}: cannot be written (No space left on device)")
        return real(path, write)

    monkeypatch.setattr(fileio, "atomic_write", full_disk_at_b)
    with pytest.raises(OSError, match="No space left"):
        fileio.write_output_files(tmp_path, {"a.csv": b"1", "b.csv": b"2"})
    assert (tmp_path / "a.csv").read_bytes() == b"1"
    monkeypatch.setattr(fileio, "atomic_write", real)
    fileio.write_output_files(tmp_path, {"a.csv": b"3", "b.csv": b"4"})
    assert [(tmp_path / n).read_bytes() for n in ("a.csv", "b.csv")] == [b"3", b"4"]


def test_unsupported_extension(tmp_path):
    with pytest.raises(LogFormatError, match="extension"):
        write_log(circle_log(), tmp_path / "log.txt")


def test_unreadable_files_are_refused_naming_the_file(tmp_path):
    """An empty file, a plain CSV named .csv.gz and a truncated archive: a LogFormatError
    that names the file, not the parser's traceback; a missing file: FileNotFoundError."""
    good = tmp_path / "good.csv.gz"
    write_log(circle_log(), good)
    cases = {"empty.csv": (b"", "the file is empty"),
             "plain.csv.gz": (b"time_s,north_m\n0,1\n", "not gzip-compressed: plain text"),
             "truncated.csv.gz": (good.read_bytes()[: len(good.read_bytes()) // 2], "not a complete gzip file"),
             "ragged.csv": (b"time_s\n0\n1,2\n", "line 3 has 2 fields where the lines before it have 1"),
             "text.parquet": (b"time_s\n0\n", "not a Parquet file"),
             "quote.csv": (b"time_s,north_m\n0,1\n1,\"2\n2,3\n", r"a quote \(\"\) opened in data row \d+ is never closed")}
    for name, (data, why) in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(LogFormatError, match=f"{name}: cannot be read as a .*{why}") as err:
            read_log(tmp_path / name)
        assert "Error" not in str(err.value), str(err.value)     # no parser's exception name
    with pytest.raises(FileNotFoundError, match="missing.csv"):
        read_log(tmp_path / "missing.csv")
    lines = gzip.decompress(good.read_bytes()).decode().splitlines()
    lines[0] += ",north_m"                         # pandas would read the second one as north_m.1
    lines[1:] = [line + ",5" for line in lines[1:]]
    (tmp_path / "dup.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(LogFormatError, match=r"north_m: column appears more than once; .*dup.csv"):
        read_log(tmp_path / "dup.csv")
    (tmp_path / "folder.csv").mkdir()
    with pytest.raises(IsADirectoryError, match="folder.csv: is a folder; expected a log file"):
        read_log(tmp_path / "folder.csv")


def test_a_csv_cut_short_in_its_last_line_leaves_that_row_out_and_says_so(tmp_path):
    """A file cut mid-line (still being written, a copy interrupted): pandas filled the short
    row with NaN and read its cut value as a number (wind from 3 deg for 336.45), silently.
    A complete last line without a line end is a whole sample and is kept."""
    path = tmp_path / "log.csv"
    write_log(circle_log(), path)
    text = path.read_text()
    last = text.splitlines()[-1]
    cut = text[: len(text) - len(last) - 1 + last.index(",", last.index(",") + 1) + 3]
    path.write_text(cut)
    with pytest.warns(LogFormatWarning, match=r"log.csv: the last line has 3 of the header's \d+ fields and no "
                                              r"line end: cut short .*its row \(row 119\) is left out"):
        df = read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)
    assert len(df) == 119 and df.notna().all().all()
    path.write_text(text.rstrip("\n"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)) == 120



def test_a_csv_with_cr_line_ends_is_read_and_its_cut_last_line_found(tmp_path):
    """A file with CR line ends (an old Mac export), which pandas reads, failed in the csv
    module's words ('new-line character seen in unquoted field') when its last line was
    looked at; it is read, and a last line cut short in it is left out as in other files."""
    text = "time_s,north_m,east_m,heading_deg\r0,0,0,10\r1,1,0,10\r2,2,0,10\r"
    path = tmp_path / "log.csv"
    path.write_bytes(text.encode())
    assert read_log(path).shape == (3, 4)
    path.write_bytes(text.encode()[:-1])            # a complete last line without its line end
    assert read_log(path).shape == (3, 4)
    path.write_bytes(text.encode()[:-4])            # cut short: "2,2,0"
    with pytest.warns(LogFormatWarning, match=r"the last line has 3 of the header's 4 fields and no line end"):
        assert read_log(path).shape == (2, 4)

def test_csv_rows_longer_than_the_header_are_refused_not_read_shifted(tmp_path):
    """Every data row one field longer than the header: pandas took the first field as the
    index and shifted every column by one (time_s held north_m's values), and the log was
    accepted; with a ',' at the end of each line heading_deg was blamed as empty."""
    write_log(circle_log(), tmp_path / "log.csv")
    text = (tmp_path / "log.csv").read_text()
    head, *rows = text.splitlines()
    n = head.count(",") + 1
    for name, body in (("extra.csv", [r + ",5" for r in rows]), ("trailing.csv", [r + "," for r in rows])):
        (tmp_path / name).write_text("\n".join([head, *body]) + "\n")
        with pytest.raises(LogFormatError, match=rf"{name}: cannot be read as a csv log file \(its data rows have "
                                                 rf"{n + 1} fields where the header has {n}"):
            read_log(tmp_path / name, validate=False)


def test_csv_columns_without_a_name_are_not_taken_for_one_name_twice(tmp_path):
    """Two empty names in the header (a spreadsheet export with empty columns) were read as
    NaN and refused as 'nan: column appears more than once'; like one, they are columns
    without a name, ignored with a warning. A name repeated is still refused."""
    write_log(circle_log(), tmp_path / "log.csv")
    head, *rows = (tmp_path / "log.csv").read_text().splitlines()
    path = tmp_path / "empty_names.csv"
    path.write_text("\n".join([head + ",,", *(r + ",1,2" for r in rows)]) + "\n")
    with pytest.warns(LogFormatWarning, match=r"Unnamed: \d+ \(a column without a name"):
        df = read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)
    assert len(df) == len(rows)
    path.write_text("\n".join([head + ",NA,NA", *(r + ",1,2" for r in rows)]) + "\n")
    with pytest.raises(LogFormatError, match=r"^NA: column appears more than once"):
        read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)


def test_a_frame_indexed_by_time_is_named_so():
    """A DataFrame indexed by time_s (set_index): time_s was said to be missing, by the
    reader's check and by ingest alike, while the frame holds it."""
    from hybridship.logs.ingest import ingest

    df = circle_log().set_index("time_s")
    before = df.copy(deep=True)
    pattern = r"^time_s: the DataFrame's index, not a column .*pass df.reset_index\(\) \(in log\)$"
    with pytest.raises(LogFormatError, match=pattern):
        validate_log(df)
    for kw in ({}, {"purpose": "forecast", "time_range_s": (10.0, 20.0)}):
        with pytest.raises(LogFormatError, match=pattern):
            ingest(df, "gunnerus", **kw)
    pd.testing.assert_frame_equal(df, before)


def test_a_parquet_log_indexed_by_time_is_named_so(tmp_path):
    """A frame indexed by time_s saved with to_parquet: time_s was said to be missing (the
    reader dropped the file's index) while the file holds it."""
    circle_log().set_index("time_s").to_parquet(tmp_path / "log.parquet")
    with pytest.raises(LogFormatError, match=r"^time_s: stored as the Parquet file's index, not as a column") as err:
        read_log(tmp_path / "log.parquet", validate=False)
    assert err.value.column == "time_s"


# --------------------------------------------------------------------------------------
# Validation errors name the column
# --------------------------------------------------------------------------------------


def _set(col, row, value):
    def mutate(df):
        df[col] = df[col].astype(object if isinstance(value, str) else float)
        df.loc[row, col] = value
        return df

    return mutate


def _radian_heading(df):
    df["heading_deg"] = np.radians(df["heading_deg"])
    return df


def _radian_heading_no_rate(df):
    return _radian_heading(df.drop(columns="r_deg_s"))


BAD_CASES = {
    "missing heading": (lambda df: df.drop(columns="heading_deg"), r"heading_deg: required column missing"),
    "missing time": (lambda df: df.drop(columns="time_s"), r"time_s: required column missing"),
    "nan north": (_set("north_m", 7, np.nan), r"north_m: missing or non-finite value \(nan\) at row 7 \(time_s 7\)"),
    "text east": (_set("east_m", 4, "12,5"), r"east_m: non-numeric value '12,5' at row 4 \(time_s 4\)"),
    "time repeat": (_set("time_s", 17, 16.0), r"time_s: not strictly increasing at row 17 \(time_s 16 after 16\)"),
    "time backwards": (_set("time_s", 30, 5.0), r"time_s: not strictly increasing at row 30"),
    "time nan": (_set("time_s", 9, np.nan), r"time_s: non-finite value nan at row 9"),
    "heading radians": (_radian_heading, r"heading_deg: values span 0\.\d\d\.\.6\.\d\d, which looks like radians"),
    "heading radians no r": (_radian_heading_no_rate, r"heading_deg: .*looks like radians.*expects degrees"),
    "u knots": (_set("u_m_s", 12, 38.0), r"u_m_s: value 38 at row 12 \(time_s 12\).*knots"),
    "v knots": (_set("v_m_s", 2, -31.0), r"v_m_s: .*knots"),
    "r rad/s mix-up": (_set("r_deg_s", 5, 70.0), r"r_deg_s: value 70 at row 5.*rad/s"),
    "wind negative": (_set("wind_speed_m_s", 8, -1.0), r"wind_speed_m_s: value -1 at row 8"),
    "wind huge": (_set("wind_speed_m_s", 8, 95.0), r"wind_speed_m_s: value 95"),
    "dp_active 2": (_set("dp_active", 11, 2.0), r"dp_active: value 2 at row 11"),
    "inf rpm": (_set("port_rpm", 6, np.inf), r"port_rpm: infinite value inf at row 6"),
    # review: read as 0/1 and as the real part (pandas' ComplexWarning only)
    "bool north": (lambda df: df.assign(north_m=df.north_m > 0), r"north_m: True/False values; expected numbers"),
    # True/False beside a missing value are objects, which were read as 1/0 (a speed of 1 m/s)
    "bool u with a gap": (lambda df: df.assign(u_m_s=(df.u_m_s > 0).astype(object).where(df.index != 3, None)),
                          r"u_m_s: True/False values; expected numbers"),
    "complex north": (lambda df: df.assign(north_m=df.north_m + 50j), r"north_m: complex values; expected real"),
    "unknown thruster rpm": (
        lambda df: df.assign(bow2_rpm=0.0),
        r"bow2_rpm: names unknown thruster or rudder 'bow2'; the vessel's thrusters and rudders: tunnel, "
        r"port, stbd",
    ),
    "unknown thruster azimuth": (
        lambda df: df.rename(columns={"stbd_azimuth_deg": "sb_azimuth_deg"}),
        r"sb_azimuth_deg: names unknown thruster or rudder 'sb'",
    ),
}


@pytest.mark.parametrize("case", list(BAD_CASES))
def test_bad_input_raises_naming_column(case):
    mutate, pattern = BAD_CASES[case]
    df = mutate(circle_log())
    before = df.copy(deep=True)
    with pytest.raises(LogFormatError, match=pattern):
        validate_log(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    pd.testing.assert_frame_equal(df, before)


def test_log_format_messages_point_at_the_likely_cause(tmp_path):
    """A header written with ', ' or ';' between names, and half a wind measurement: the
    message says what is wrong, not only what is missing."""
    df = circle_log()
    spaced, semi = tmp_path / "spaced.csv", tmp_path / "semi.csv"
    spaced.write_text(df.to_csv(index=False).replace(",", ", "))
    df.to_csv(semi, index=False, sep=";", decimal=",")
    with pytest.raises(LogFormatError, match=r"found ' north_m', which is north_m with spaces around the name") as err:
        read_log(spaced)
    assert "another unit" not in str(err.value)          # one hint, not two that disagree
    with pytest.raises(LogFormatError, match=r"the header is one name holding ';'"):
        read_log(semi)
    for missing in ("wind_dir_deg", "wind_speed_m_s"):
        with pytest.raises(LogFormatError, match=rf"^{missing}: missing while"):
            validate_log(df.drop(columns=[missing]), channel_names=THRUSTERS, rotatable=ROTATABLE)
    validate_log(df.drop(columns=["wind_dir_deg", "wind_speed_m_s"]), channel_names=THRUSTERS, rotatable=ROTATABLE)


def test_error_attributes_and_file_name(tmp_path):
    df = circle_log()
    df.loc[7, "north_m"] = np.nan
    path = tmp_path / "broken.csv"
    df.to_csv(path, index=False)  # bypass write_log's validation
    with pytest.raises(LogFormatError, match=r"north_m: .*broken\.csv") as info:
        read_log(path)
    err = info.value
    assert isinstance(err, ValueError)
    assert (err.column, err.row, err.time_s) == ("north_m", 7, 7.0)


def test_thruster_argument_mismatch():
    with pytest.raises(ValueError, match="rotatable"):
        validate_log(circle_log(), channel_names=THRUSTERS, rotatable=[True])


# --------------------------------------------------------------------------------------
# Heading unit rule
# --------------------------------------------------------------------------------------


def test_small_degree_headings_are_accepted():
    t = np.arange(600.0)
    heading = 1.5 + 1.5 * np.sin(2 * np.pi * t / 300.0)  # all within 0..3 deg
    rate = np.gradient(heading, t)
    assert not heading_looks_like_radians(t, heading)[0]
    assert not heading_looks_like_radians(t, heading, rate)[0]
    # without the velocities, which a replaced heading no longer turns onto the track
    df = circle_log(600).assign(heading_deg=heading, r_deg_s=rate).drop(columns=["u_m_s", "v_m_s"])
    validate_log(df)
    validate_log(df.drop(columns="r_deg_s"))


def test_radian_headings_are_refused():
    t = np.arange(600.0)
    # A turn spanning 0..6.28 without wrapping, no rate column: refused by its spread.
    assert heading_looks_like_radians(t, np.linspace(0.0, 2 * np.pi, t.size))[0]
    # A DP log in radians barely moving: only the rate column can tell, and does.
    rng = np.random.default_rng(1)
    psi_deg = 92.0 + np.cumsum(rng.normal(0.0, 0.05, t.size))
    r_deg_s = np.gradient(psi_deg, t) + rng.normal(0.0, 0.01, t.size)
    assert heading_looks_like_radians(t, np.radians(psi_deg), r_deg_s)[0]
    assert not heading_looks_like_radians(t, psi_deg, r_deg_s)[0]


def test_a_radian_heading_that_wraps_is_refused_even_with_its_rate_in_rad_s():
    """A radian heading wrapping at 2 pi, logged with its rate in rad/s (which alone would say
    degrees): the one-sample jump of about 2 pi among small steps decides, and is named."""
    t = np.arange(120.0)
    rate = 0.01 + 0.005 * np.sin(t / 10.0)                    # rad/s, logged in r_deg_s
    psi = np.mod(5.9 + np.concatenate(([0.0], np.cumsum(0.5 * (rate[1:] + rate[:-1])))), 2 * np.pi)
    is_rad, reason = heading_looks_like_radians(t, psi, rate)
    assert is_rad and reason.startswith("it jumps by -6.2")
    # the jump's times as the log has them: epoch times were written "1.7e+09 and 1.7e+09"
    k = int(np.argmax(np.abs(np.diff(psi)) > np.pi))
    reason = heading_looks_like_radians(1.7e9 + t, psi, rate)[1]
    assert f"between time_s {1700000000 + k} and {1700000000 + k + 1} " in reason


# --------------------------------------------------------------------------------------
# Unknown columns
# --------------------------------------------------------------------------------------


def test_unknown_columns_warn_once_and_are_kept(tmp_path):
    df = circle_log().assign(gps_quality=1, pitch_deg=0.0, tunnel_azimuth_deg=0.0)
    path = tmp_path / "log.csv"
    df.to_csv(path, index=False)
    with pytest.warns(LogFormatWarning) as record:
        back = read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)
    msgs = [str(w.message) for w in record if issubclass(w.category, LogFormatWarning)]
    assert len(msgs) == 1
    assert "gps_quality" in msgs[0] and "pitch_deg" in msgs[0] and "not rotatable" in msgs[0]
    assert "truth_" not in msgs[0]
    assert {"gps_quality", "pitch_deg", "truth_current_speed_mps"} <= set(back.columns)
    df.to_csv(path)         # the frame's index saved with it: pandas calls its column "Unnamed: 0"
    with pytest.warns(LogFormatWarning, match=r"Unnamed: 0 \(a column without a name: an index saved with to_csv\?\)"):
        read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)


def test_format_columns_do_not_warn():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        validate_log(circle_log(), channel_names=THRUSTERS, rotatable=ROTATABLE)


# --------------------------------------------------------------------------------------
# Arrays
# --------------------------------------------------------------------------------------


def test_derived_velocities_on_circle_match_analytic():
    df = circle_log(120, velocities=False)
    arr = log_to_arrays(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    w = np.radians(R_DEG_S)
    assert not arr.nu_logged.any()
    # Heading unwrapped across north: a steady turn.
    np.testing.assert_allclose(np.diff(arr.eta[:, 2]), w, atol=1e-9)
    inner = slice(1, -1)  # central differences inside; one-sided at the ends
    np.testing.assert_allclose(arr.nu[inner, 0], U_M_S, atol=1e-3)
    np.testing.assert_allclose(arr.nu[inner, 1], V_M_S, atol=1e-3)
    np.testing.assert_allclose(arr.nu[:, 2], w, atol=1e-9)
    np.testing.assert_allclose(arr.nu[:, :2], [[U_M_S, V_M_S]] * len(arr), atol=0.05)


def test_logged_velocities_are_used_and_converted():
    df = circle_log(60)
    # logged values a little off the track's (a log's own sensors): taken as logged, not the
    # velocities derived from the track, which on this circle are U, V and R within 1e-3
    t = df.time_s.to_numpy()
    df["u_m_s"] += 0.02 * np.cos(t / 7.0)
    df["v_m_s"] -= 0.02 * np.sin(t / 5.0)
    df["r_deg_s"] += 0.02 * np.sin(t / 3.0)
    df.loc[10, "u_m_s"] = np.nan  # a missing sample is derived instead
    arr = log_to_arrays(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    np.testing.assert_allclose(arr.nu[:, 2], np.radians(df.r_deg_s), rtol=1e-12)
    np.testing.assert_allclose(arr.nu[:, 1], df.v_m_s, rtol=1e-12)
    logged_u = np.arange(60) != 10
    np.testing.assert_allclose(arr.nu[logged_u, 0], df.u_m_s[logged_u], rtol=1e-12)
    assert arr.nu_logged[:, 1:].all() and arr.nu_logged.sum() == 3 * 60 - 1
    assert not arr.nu_logged[10, 0]
    np.testing.assert_allclose(arr.nu[10, 0], U_M_S, atol=1e-3)


def test_log_to_arrays_commands_wind_and_defaults():
    df = circle_log(40)
    df.loc[4, "port_rpm"], df.loc[8, "port_rpm"] = 100.0, 140.0   # the values either side of a gap differ
    df.loc[5:7, "port_rpm"] = np.nan
    arr = log_to_arrays(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    n = len(df)
    assert arr.eta.shape == arr.nu.shape == (n, 3)
    assert arr.rpm.shape == arr.azimuth_rad.shape == (n, 3)
    np.testing.assert_allclose(arr.rpm[:, 0], df["tunnel_rpm"])
    # the last logged value held over the missing samples: not the next one, nor between them
    np.testing.assert_allclose(arr.rpm[4:9, 1], [100.0, 100.0, 100.0, 100.0, 140.0])
    np.testing.assert_allclose(arr.rpm[:, 2], df["stbd_rpm"])
    np.testing.assert_allclose(arr.azimuth_rad[:, 0], 0.0)  # tunnel: fixed
    np.testing.assert_allclose(arr.azimuth_rad[:, 1:], np.radians([[-30.0, 30.0]] * n))
    assert arr.has_wind
    np.testing.assert_allclose(arr.wind[:, 0], df["wind_speed_m_s"])   # m/s as logged
    np.testing.assert_allclose(arr.wind[:, 1], np.radians(45.0))
    np.testing.assert_array_equal(arr.dp_active, df["dp_active"])
    np.testing.assert_array_equal(arr.segment_id, 0)
    with pytest.raises(ValueError):
        arr.eta[0, 0] = 1.0  # read-only

    bare = df[["time_s", "north_m", "east_m", "heading_deg"]]
    arr = log_to_arrays(bare, channel_names=THRUSTERS, rotatable=ROTATABLE)
    assert not arr.has_wind and np.all(arr.wind == 0.0)
    assert np.all(arr.dp_active == 1) and np.all(arr.rpm == 0.0)
    assert arr.channel_logged == (False, False, False)
    assert np.isfinite(arr.nu).all()


def test_log_to_arrays_does_not_differentiate_across_gaps():
    df = circle_log(100, velocities=False)
    # Remove 20 samples and shift the track after the gap: a naive derivative would spike.
    df = df.drop(index=range(40, 60)).reset_index(drop=True)
    df.loc[40:, "north_m"] += 500.0
    arr = log_to_arrays(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
    assert [(s.start, s.stop) for s in arr.segments] == [(0, 40), (40, 80)]
    np.testing.assert_array_equal(arr.segment_id, np.repeat([0, 1], 40))
    np.testing.assert_allclose(arr.nu[:, :2], [[U_M_S, V_M_S]] * 80, atol=0.05)


# --------------------------------------------------------------------------------------
# Preprocessing
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["savgol", "butter"])
def test_filtered_derivative_of_sine(method):
    dt_s, f_hz = 0.5, 0.02
    t = np.arange(0.0, 200.0, dt_s)
    x = np.sin(2 * np.pi * f_hz * t)
    rng = np.random.default_rng(0)
    dx = filtered_derivative(x + rng.normal(0.0, 1e-4, t.size), dt_s, method=method, window_s=5.0)
    expected = 2 * np.pi * f_hz * np.cos(2 * np.pi * f_hz * t)
    inner = slice(40, -40)
    np.testing.assert_allclose(dx[inner], expected[inner], atol=2e-3 * 2 * np.pi * f_hz * 10)


def test_filtered_derivative_axis_and_short_segments():
    t = np.arange(50.0)
    x = np.column_stack([t**2, 3.0 * t])
    np.testing.assert_allclose(filtered_derivative(x, 1.0)[5:-5], np.column_stack([2 * t, np.full(50, 3.0)])[5:-5])
    np.testing.assert_allclose(filtered_derivative(x.T, 1.0, axis=1).T, filtered_derivative(x, 1.0))
    short = np.array([0.0, 2.0, 4.0])  # shorter than the 5-sample window: np.gradient
    np.testing.assert_allclose(filtered_derivative(short, 1.0), 2.0)
    assert np.isnan(filtered_derivative(np.array([1.0]), 1.0)).all()
    with pytest.raises(ValueError, match="method"):
        filtered_derivative(short, 1.0, method="spline")


def test_filtered_derivative_refuses_a_window_or_order_that_gives_no_derivative():
    """A window of 0 s raised ZeroDivisionError (butter), NaN numpy's integer conversion, and a
    negative one was used as the shortest window; a polynomial of order 0 has derivative 0
    everywhere and a Butterworth filter of order 0 filters nothing: both came back silently."""
    t = np.arange(40.0)
    x = t**2
    for kw, field in (({"method": "butter", "window_s": 0.0}, "window_s"), ({"window_s": np.nan}, "window_s"),
                      ({"window_s": -5.0}, "window_s"), ({"polyorder": 0}, "polyorder"),
                      ({"polyorder": 2.5}, "polyorder"),
                      ({"method": "butter", "cutoff_hz": 0.2, "butter_order": 0}, "butter_order")):
        with pytest.raises(ValueError, match=f"^filtered_derivative: {field}: "):
            filtered_derivative(x, 1.0, **kw)
    np.testing.assert_allclose(filtered_derivative(x, 1.0, polyorder=1)[5:-5], 2 * t[5:-5])


def test_filtered_derivative_names_an_axis_that_x_does_not_have():
    """An axis beyond x's dimensions, a fractional or None one, or a single number failed in
    numpy's words ("tuple index out of range"), naming neither axis nor x."""
    x = np.arange(40.0) ** 2
    for kw in ({"axis": 1}, {"axis": -2}, {"axis": 1.0}, {"axis": None}, {"method": "butter", "axis": 1}):
        with pytest.raises(ValueError, match="^filtered_derivative: axis: "):
            filtered_derivative(x, 1.0, **kw)
    with pytest.raises(ValueError, match="^filtered_derivative: axis: "):
        filtered_derivative(3.0, 1.0)
    np.testing.assert_allclose(filtered_derivative(np.stack([x, x]), 1.0, axis=-1), filtered_derivative(x, 1.0)[None]
                               .repeat(2, 0))


def test_filtered_derivative_names_a_sample_period_or_cut_off_that_is_not_a_number():
    """dt_s and cutoff_hz went through float(): text was read as a number ("2" as 2 s), True
    was 1 s, and None or "a" failed in float()'s words, naming neither argument."""
    x = np.arange(40.0) ** 2
    for bad in ("a", "2", True, None):
        with pytest.raises(TypeError, match="^filtered_derivative: dt_s: expected a number"):
            filtered_derivative(x, bad)
        with pytest.raises(TypeError, match="^filtered_derivative: cutoff_hz: expected a number"):
            filtered_derivative(x, 1.0, method="butter", cutoff_hz="a" if bad is None else bad)
    for bad in (-1.0, 0.0, np.nan):
        with pytest.raises(ValueError, match="^filtered_derivative: dt_s: "):
            filtered_derivative(x, bad)
    with pytest.raises(ValueError, match="^filtered_derivative: cutoff_hz: "):
        filtered_derivative(x, 1.0, method="butter", cutoff_hz=np.nan)
    np.testing.assert_allclose(filtered_derivative(x, 1.0, method="butter", cutoff_hz=0.2),
                               filtered_derivative(x, 1.0, method="butter", window_s=5.0))


def test_split_segments_refuses_a_gap_factor_that_is_not_a_number_above_1():
    """A gap factor below 1 made every step a gap (a segment per sample) and NaN made none."""
    t = np.arange(10.0)
    for bad in (-1.0, 0.5, 1.0, np.nan):
        with pytest.raises(ValueError, match="^split_segments: gap_factor: "):
            split_segments(t, gap_factor=bad)


def test_split_segments_names_a_nominal_period_that_is_not_a_number():
    """Text was read as a number ("2" as 2 s) or failed in float()'s words, True was 1 s."""
    t = np.arange(10.0)
    for bad in ("a", "2", True):
        with pytest.raises(TypeError, match="^split_segments: nominal_dt_s: expected a number"):
            split_segments(t, nominal_dt_s=bad)
    for bad in (-1.0, 0.0, np.nan):
        with pytest.raises(ValueError, match="^split_segments: nominal_dt_s: "):
            split_segments(t, nominal_dt_s=bad)


def test_split_segments_and_segmentwise_derivative():
    t = np.concatenate([np.arange(0.0, 50.0), np.arange(60.0, 100.0), [100.0, 101.4]])
    segs = split_segments(t)
    assert [(s.start, s.stop) for s in segs] == [(0, 50), (50, 92)]  # 1.4 s is not a gap
    assert [(s.start, s.stop) for s in split_segments(t, gap_factor=1.3)] == [(0, 50), (50, 91), (91, 92)]
    assert [(s.start, s.stop) for s in split_segments(t, nominal_dt_s=10.0)] == [(0, 92)]
    # a step of exactly gap_factor nominal periods is not a gap, a longer one is
    assert split_segments([0.0, 1.0, 2.0, 3.5, 4.5, 5.5]) == [slice(0, 6)]
    assert split_segments([0.0, 1.0, 2.0, 3.6, 4.6, 5.6]) == [slice(0, 3), slice(3, 6)]
    assert split_segments([]) == [] and split_segments([3.0]) == [slice(0, 1)]
    with pytest.raises(ValueError, match="strictly increasing"):
        split_segments([0.0, 1.0, 1.0])
    for bad in ([np.nan], [0.0, np.inf]):       # one sample as the docstring says, not a segment
        with pytest.raises(ValueError, match="time_s must be finite"):
            split_segments(bad)

    t = t[:90]  # uniform sampling within each segment, one gap
    x = t.copy()
    x[50:] += 1000.0  # a jump hidden in the gap
    dx = derivative_by_segment(x, t, window_s=5.0)
    np.testing.assert_allclose(dx, 1.0, atol=1e-9)
    naive = filtered_derivative(x, 1.0)
    assert np.abs(naive).max() > 100.0  # what segmentwise prevents
    segs = split_segments(t)

    out = segmentwise(lambda a: a - a[0], x, segs)
    assert out[0] == 0.0 and out[50] == 0.0
    np.testing.assert_array_equal(segmentwise(lambda a: a, x, [slice(0, 10)])[10:], np.nan)


def test_moving_average_start_refuses_a_fractional_row_or_window_and_a_short_segment_id():
    """A row 2.0 or a window of 2.5 samples failed in slicing ("slice indices must be
    integers"), a segment label array shorter than ``x`` with numpy's IndexError."""
    x = np.arange(10.0)
    with pytest.raises(ValueError, match="^moving_average_start: idx: expected a whole number"):
        moving_average_start(x, 2.0)
    with pytest.raises(ValueError, match="^moving_average_start: window_samples: expected a whole number >= 1"):
        moving_average_start(x, 5, 2.5)
    with pytest.raises(ValueError, match=r"^moving_average_start: segment_id: expected one label per row \(10,\)"):
        moving_average_start(x, 5, segment_id=[0, 0, 1])
    assert moving_average_start(x, np.int64(5), np.int64(2)) == 4.5


def test_moving_average_start():
    x = np.column_stack([np.arange(10.0), 10.0 * np.arange(10.0)])
    np.testing.assert_allclose(moving_average_start(x, 5), [4.0, 40.0])
    np.testing.assert_allclose(moving_average_start(x, 0), [0.0, 0.0])  # shorter window at the start
    np.testing.assert_allclose(moving_average_start(x, -1, window_samples=4), [7.5, 75.0])
    seg = np.array([0] * 5 + [1] * 5)
    np.testing.assert_allclose(moving_average_start(x, 6, segment_id=seg), [5.5, 55.0])  # stops at the gap
    # Unwrapped heading averages smoothly across north.
    psi = frames.unwrap_heading(np.radians([358.0, 359.0, 1.0]))
    np.testing.assert_allclose(np.degrees(moving_average_start(psi, 2)), (358.0 + 359.0 + 361.0) / 3.0)
    with pytest.raises(IndexError):
        moving_average_start(x, 10)


# --------------------------------------------------------------------------------------
# The development data set
# --------------------------------------------------------------------------------------


def _dev_logs(shared_data) -> list[Path]:
    folder = shared_data("truthsim-dev", "logs")
    logs = sorted(folder.glob("*.csv.gz"))
    if not logs:
        pytest.skip(f"no development logs (*.csv.gz) in {folder}")
    return logs


def _increments(x: np.ndarray, lag: int) -> np.ndarray:
    return x[lag:] - x[:-lag]


def test_dev_logs_read_and_velocities_match_heading(shared_data):
    from scipy.integrate import cumulative_trapezoid

    lag = 20  # compare 20-s displacements: GNSS noise is small against them
    for path in _dev_logs(shared_data):
        with warnings.catch_warnings():
            warnings.simplefilter("error", LogFormatWarning)  # only format and truth_* columns
            df = read_log(path, channel_names=THRUSTERS, rotatable=ROTATABLE)
        arr = log_to_arrays(df, channel_names=THRUSTERS, rotatable=ROTATABLE)
        assert arr.nu_logged.all() and arr.has_wind and all(arr.channel_logged), path.name
        assert set(np.unique(arr.dp_active)) == {0, 1} and len(arr.segments) == 1, path.name

        # Logged (u, v) rotated to NED with the logged heading and integrated, against the
        # displacement of the track. As complex numbers north + i east, the regression
        # coefficient's angle is the heading mismatch (a 5 deg offset gives 5 deg).
        ned_m_s = frames.body_to_ned(arr.nu, arr.eta[:, 2])[:, :2]
        from_velocity = _increments(cumulative_trapezoid(ned_m_s, arr.time_s, axis=0, initial=0.0), lag)
        from_track = _increments(arr.eta[:, :2], lag)
        for j, axis in enumerate(("north", "east")):
            corr = np.corrcoef(from_velocity[:, j], from_track[:, j])[0, 1]
            assert corr > 0.9, f"{path.name}: {axis} displacement correlation {corr:.3f}"
        zv, zt = from_velocity @ [1.0, 1.0j], from_track @ [1.0, 1.0j]
        coef = np.vdot(zv, zt) / np.vdot(zv, zv)
        assert abs(np.degrees(np.angle(coef))) < 2.0, f"{path.name}: heading mismatch {np.degrees(np.angle(coef)):.2f} deg"
        assert 0.95 < abs(coef) < 1.05, f"{path.name}: speed scale {abs(coef):.3f}"

        # Logged yaw rate integrated against the unwrapped heading's change.
        from_rate = _increments(cumulative_trapezoid(arr.nu[:, 2], arr.time_s, initial=0.0), lag)
        from_heading = _increments(arr.eta[:, 2], lag)
        assert np.corrcoef(from_rate, from_heading)[0, 1] > 0.95, path.name
        slope = np.dot(from_rate, from_heading) / np.dot(from_rate, from_rate)
        assert 0.95 < slope < 1.05, f"{path.name}: yaw rate scale {slope:.3f}"


def test_the_column_spec_is_the_documented_format():
    """Every column of the declarative spec is in the log-format page's table, with its unit
    and whether it is required; and nothing else is required."""
    from conftest import ROOT
    from hybridship.logs.columns import COLUMNS, REQUIRED_COLUMNS

    rows = [line for line in (ROOT / "docs" / "reference" / "log-format.md").read_text(encoding="utf-8").splitlines()
            if line.startswith("| `")]
    for spec in COLUMNS:
        row = next((r for r in rows if f"`{spec.name}`" in r.split("|")[1]), None)
        assert row is not None, spec.name
        unit, required = (c.strip() for c in row.split("|")[2:4])
        assert unit == (spec.unit or "0/1"), spec.name
        assert required == ("yes" if spec.required else "no"), spec.name
    assert REQUIRED_COLUMNS == ("time_s", "north_m", "east_m", "heading_deg")



def test_a_plausible_range_includes_its_ends():
    """Bound.violated: a value at the limit is accepted, one beyond it refused, NaN passes."""
    from hybridship.logs.columns import Bound

    np.testing.assert_array_equal(Bound(hi=30.0, magnitude=True).violated(np.array([30.0, -30.0, 30.5, -30.5, np.nan])),
                                  [False, False, True, True, False])
    np.testing.assert_array_equal(Bound(0.0, 80.0).violated(np.array([0.0, 80.0, -0.1, 80.1])),
                                  [False, False, True, True])


def test_datetime_times_and_gzip_named_csv_are_named_for_what_they_are(tmp_path):
    """time_s as pandas datetimes is not read as nanoseconds (and then blamed on milliseconds);
    a gzip file named .csv is said to be gzip, not a decoding error."""
    import gzip

    df = circle_log()
    stamped = df.assign(time_s=pd.to_datetime(df.time_s, unit="s"))
    with pytest.raises(LogFormatError, match=r"time_s: datetime64\[\w+\] values; expected plain numbers") as err:
        validate_log(stamped, channel_names=THRUSTERS, rotatable=ROTATABLE)
    assert "milliseconds" not in str(err.value)
    # periods were read as counts of their unit: minutes accepted as seconds, unremarked
    minutes = df.assign(time_s=pd.period_range("2024-01-01", periods=len(df), freq="min"))
    with pytest.raises(LogFormatError, match=r"time_s: period\[min\] values; expected plain numbers .*"
                                             r"after t = t\.dt\.to_timestamp\(\)"):
        validate_log(minutes, channel_names=THRUSTERS, rotatable=ROTATABLE)
    path = tmp_path / "log.csv"
    path.write_bytes(gzip.compress(df.to_csv(index=False).encode()))
    with pytest.raises(LogFormatError, match=r"log.csv: is gzip-compressed; name it log.csv.gz"):
        read_log(path)
    plain = tmp_path / "plain.csv.gz"       # and the reverse: a plain CSV named .csv.gz
    df.to_csv(plain, index=False, compression=None)
    with pytest.raises(LogFormatError, match=r"plain.csv.gz: .*not gzip-compressed: plain text\? name it plain.csv,"):
        read_log(plain)


def test_something_that_is_not_a_path_is_named_as_such():
    from hybridship.predictors import HybridPredictor
    from hybridship.vessel import load_vessel

    for call in (lambda: read_log(None), lambda: read_log(pd.DataFrame()), lambda: write_log(circle_log(), None),
                 lambda: HybridPredictor.load(None)):
        with pytest.raises(TypeError, match=r"^path: expected a file path \(str or os.PathLike\), got "):
            call()
    for call in (lambda: load_vessel(None), lambda: HybridPredictor(None)):
        with pytest.raises(TypeError, match="^vessel: expected a packaged vessel name or a vessel file path"):
            call()


def test_writing_keeps_an_unknown_column_and_says_readers_ignore_it(tmp_path):
    from hybridship.logs.io import LogFormatWarning

    df = circle_log().assign(winch_load_kN=1.0)
    with pytest.warns(LogFormatWarning, match=r"writing, though readers ignore them, 1 column\(s\) not in the log "
                                              r"format: winch_load_kN"):
        write_log(df, tmp_path / "log.csv")
    assert "winch_load_kN" in pd.read_csv(tmp_path / "log.csv").columns        # the user's column kept
    with pytest.warns(LogFormatWarning, match="ignoring 1 column"):
        read_log(tmp_path / "log.csv")


def test_an_output_folder_that_cannot_be_made_is_named(tmp_path):
    """Path.mkdir named only the first folder it could not make, not the output folder given."""
    from hybridship.fileio import make_out_folder

    blocker = tmp_path / "a_file"
    blocker.write_text("x")
    with pytest.raises(OSError, match=r"a_file/out: cannot make the output folder \("):
        make_out_folder(blocker / "out")
    assert make_out_folder(tmp_path / "new" / "out").is_dir()


def test_a_rudder_rpm_column_is_refused_against_the_vessel():
    """A '<rudder>_rpm' column was accepted and became the rudder channel's rpm in
    LogArrays.rpm (documented as 0 in rudder channels), unremarked."""
    from hybridship.logs.io import check_log_against_vessel

    t = np.arange(120.0)
    df = pd.DataFrame({"time_s": t, "north_m": 0.5 * t, "east_m": 0.0 * t, "heading_deg": 0.0 * t + 10.0,
                       "propeller_rpm": 300.0, "rudder_azimuth_deg": 5.0, "dp_active": 0})
    check_log_against_vessel(df, "esso_osaka_model")
    with pytest.raises(LogFormatError, match=r"^rudder_rpm: 'rudder' is a rudder of vessel 'esso_osaka_model' and "
                                             r"has no rpm; expected <thruster>_rpm for the thrusters \(propeller_rpm\)"):
        check_log_against_vessel(df.assign(rudder_rpm=77.0), "esso_osaka_model")


def test_a_rudder_held_near_amidships_is_not_taken_for_radians():
    """A rudder logged in degrees within +-3 deg (course keeping) spans 6 within +-2 pi and was
    refused as radians ('a turn of 344 deg if radians'), by ingest and the whole-log check
    alike; in radians a rudder stays within +-pi/2, where the radian rule finds nothing."""
    from hybridship.logs.ingest import ingest
    from hybridship.logs.io import check_log_against_vessel, check_units_on_whole_log
    from hybridship.vessel import load_vessel

    v = load_vessel("esso_osaka_model")
    t = np.arange(600.0)
    df = pd.DataFrame({"time_s": t, "north_m": 0.5 * t, "east_m": 0.0 * t, "heading_deg": 0.0 * t + 10.0,
                       "propeller_rpm": 300.0, "rudder_azimuth_deg": 3.0 * np.sin(2 * np.pi * t / 60.0),
                       "dp_active": 0})
    check_log_against_vessel(df, v)
    check_units_on_whole_log(df, v)
    assert np.allclose(np.degrees(ingest(df, v).azimuth_rad[:, 1]), df.rudder_azimuth_deg)
    assert np.allclose(np.degrees(ingest(df, v, purpose="forecast", time_range_s=(100, 200)).azimuth_rad[:, 1]),
                       df.rudder_azimuth_deg[100:201])


def test_speed_scale_vs_track_names_a_lag_that_is_not_a_positive_number():
    """NaN failed in int() ("cannot convert float NaN to integer"), text and None in a
    division, and a negative or zero lag was used as one sample, unremarked."""
    from hybridship.logs.io import speed_scale_vs_track

    t, z = np.arange(100.0), np.zeros(100)
    for bad, err in ((np.nan, ValueError), (-5.0, ValueError), (0.0, ValueError), ("20", TypeError),
                     (None, TypeError)):
        with pytest.raises(err, match="^speed_scale_vs_track: lag_s: "):
            speed_scale_vs_track(t, 0.5 * t, z, z, z + 0.5, z, lag_s=bad)
    assert speed_scale_vs_track(t, 0.5 * t, z, z, z + 0.5, z, lag_s=10).scale == pytest.approx(1.0)


def test_the_unit_rules_name_a_column_that_is_not_one_value_per_time():
    """Columns of another length than time_s failed in numpy's words ("boolean index did
    not match", "all the input array dimensions ..."), naming no column."""
    from hybridship.logs.io import speed_scale_vs_track

    t, z = np.arange(100.0), np.zeros(100)
    with pytest.raises(ValueError, match=r"^heading_looks_like_radians: heading: expected one value per time_s"):
        heading_looks_like_radians(t[:50], z)
    with pytest.raises(ValueError, match=r"^heading_looks_like_radians: r_deg_s: expected one value per time_s"):
        heading_looks_like_radians(t, z, z[:10])
    with pytest.raises(ValueError, match=r"^speed_scale_vs_track: v_m_s: expected one value per time_s"):
        speed_scale_vs_track(t, 0.5 * t, z, z, z + 0.5, z[:99])


def test_preprocessing_names_samples_that_are_text_complex_or_a_single_number():
    """Text failed in float()'s words ("could not convert string to float: 'a'"), complex
    samples lost their imaginary part with only a warning, and a single number failed in
    numpy's "tuple index out of range", naming no argument."""
    t = np.arange(20.0)
    for call, name in ((lambda bad: filtered_derivative(bad, 1.0), "filtered_derivative: x"),
                       (lambda bad: derivative_by_segment(bad, t), "derivative_by_segment: x"),
                       (lambda bad: derivative_by_segment(np.ones(20), bad), "derivative_by_segment: time_s"),
                       (lambda bad: split_segments(bad), "split_segments: time_s"),
                       (lambda bad: moving_average_start(bad, 0), "moving_average_start: x")):
        for bad in (["a"] * 20, np.ones(20) + 1j):
            with pytest.raises(TypeError, match=f"^{name}: expected an array of real numbers"):
                call(bad)
    with pytest.raises(ValueError, match="^moving_average_start: x: a single number"):
        moving_average_start(3.0, 0)


def test_a_100_hz_log_is_accepted_at_the_end_of_the_spacing_range():
    """Spacing 0.01 s is documented as accepted, yet times of 100 Hz samples are not exact in
    binary (median step 0.0099999999999998, or 0.00999999 in epoch seconds): such logs were
    refused as 'median sample spacing 0.01 ... is time_s in minutes or hours?'."""
    for t in (np.arange(1000) * 0.01, 1.7e9 + np.arange(1000) * 0.01):
        validate_log(pd.DataFrame({"time_s": t, "north_m": 0.0, "east_m": 0.0, "heading_deg": 10.0}))
    with pytest.raises(LogFormatError, match=r"^time_s: median sample spacing 0\.009 "):
        validate_log(pd.DataFrame({"time_s": np.arange(1000) * 0.009, "north_m": 0.0, "east_m": 0.0,
                                   "heading_deg": 10.0}))
