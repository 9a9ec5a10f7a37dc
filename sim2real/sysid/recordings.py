"""Recordings of a real (or simulated) system: load, validate against a model, hold as arrays.

Format (README, "Recording format"): one table per file, a row per sample.

=====================  ===========================================================
column                 meaning
=====================  ===========================================================
``time``               seconds, strictly increasing, uniform sample rate (``MAX_PERIOD_S``; jittered
                       stamps are resampled, lost samples cut the file into pieces: ``load_pieces``)
``qpos:<joint>``       measured joint position (m or rad), at least one
``qvel:<joint>``       measured joint velocity (optional; else differentiated)
``ctrl:<actuator>``    command sent to the actuator, one per actuator of the model
``force:<actuator>``   measured actuator force (optional, e.g. from motor current)
``qfrc:<joint>``       known external generalised force on the joint (optional)
=====================  ===========================================================

CSV and other delimited text (header row; ``.tsv``, ``.txt``: :func:`_read_csv`; a unit after a name,
``qpos:hinge [rad]``, is checked: :func:`_check_units`), NPZ (arrays named like the columns), Parquet (numeric columns named like the
columns; pyarrow), MCAP (ROS 2 ``sensor_msgs/JointState``: :func:`_read_mcap`) and MATLAB ``.mat`` (variables named like the columns with ``:`` written as
``__``, e.g. ``qpos__axis``) are read. Every problem raises
:class:`RecordingError` naming the file and the column or row.
"""
from __future__ import annotations

import dataclasses
import os
import re

import mujoco
import numpy as np

KINDS = ("qpos", "qvel", "ctrl", "force", "qfrc")
_TARGET = {"qpos": "joint", "qvel": "joint", "qfrc": "joint", "ctrl": "actuator", "force": "actuator"}
# The longest sample period a recording may have, in seconds and in the model's physics steps.
# Why: a logger's milliseconds (or a ROS stamp's nanoseconds) read as seconds made every sample
# thousands of physics steps long, and the diagnosis of a 250 Hz log simulated its first segment
# for minutes without a word; no rigid-body dynamics is identified from samples this far apart.
MAX_PERIOD_S = 0.5
MAX_STEPS_PER_SAMPLE = 1000
# Time stamps further than UNIFORM of a step off the uniform grid that fits them are resampled onto
# it (``_grid``, ``resample``); a step longer than MAX_GAP median steps (samples lost) is refused.
UNIFORM = 0.01
MAX_GAP = 3.0
MIN_SAMPLES = 20  # the fewest a recording (or a piece of one cut at lost samples) may have
# A measured velocity whose integral over the time column differs from the change of its position
# by more than this share is refused (``_check_velocity_scale``): deg/s or rpm read as rad/s, a
# motor's speed before its gear, or stamps spaced by another clock than the samples'.
VEL_SCALE = 0.15
VEL_WINDOW_S = 0.5  # the windows the two displacements are compared over (a filter's lag averages out)
VEL_SE = 5.0  # ... and by this many of the ratio's standard errors


class RecordingError(ValueError):
    """A recording that cannot be used; the message names file, column and row."""


@dataclasses.dataclass
class Recording:
    """One validated recording.

    Attributes:
      path: where it came from.
      time: ``[T]`` seconds.
      columns: ``{'qpos:axis': [T], ...}`` float64 arrays.
    """

    path: str
    time: np.ndarray
    columns: dict[str, np.ndarray]
    notes: list[str] = dataclasses.field(default_factory=list)  # what loading did to the data
    rows: str = ""  # a piece of a file cut at lost samples (``load_pieces``): its data rows, "801-1570"

    @property
    def name(self) -> str:
        base = os.path.splitext(os.path.basename(self.path))[0]
        return f"{base}[rows {self.rows}]" if self.rows else base

    @property
    def where(self) -> str:
        """The file, and the rows where this is a piece of it."""
        return f"{self.path}[rows {self.rows}]" if self.rows else self.path

    @property
    def first_row(self) -> int:
        """The file's data row (from 1) of this recording's first sample."""
        return int(self.rows.split("-")[0]) if self.rows else 1

    @property
    def dt(self) -> float:
        return float(np.median(np.diff(self.time)))

    def names(self, kind: str) -> list[str]:
        return [c.split(":", 1)[1] for c in self.columns if c.startswith(kind + ":")]

    def get(self, kind: str, name: str) -> np.ndarray | None:
        return self.columns.get(f"{kind}:{name}")

    def __len__(self) -> int:
        return len(self.time)

    def slice(self, start: int, stop: int) -> "Recording":
        return Recording(f"{self.path}[{start}:{stop}]", self.time[start:stop],
                         {k: v[start:stop] for k, v in self.columns.items()})


def _read_csv(path: str) -> dict[str, np.ndarray]:
    """Delimited text with a header row, as loggers and spreadsheets write it (``.csv``, ``.tsv``,
    ``.txt``): the delimiter is the header's (comma, semicolon, tab, else runs of spaces); lines
    starting with ``#`` are comments, the last one before the data taken as the header where no
    header row follows (``np.savetxt(..., header=...)``); with a semicolon or tab a decimal comma
    reads as a point (a European spreadsheet's ``0,005``); a first column without a name holding
    0, 1, 2, ... (a pandas index, ``to_csv`` without ``index=False``) is left out. Every other
    cell must be a number (the error names row and column)."""
    import csv

    # utf-8-sig: spreadsheet programs start the file with a byte-order mark
    with open(path, newline="", encoding="utf-8-sig") as f:
        lines = f.read().splitlines()
    comments = []
    while lines and (not lines[0].strip() or lines[0].lstrip().startswith("#")):
        if lines[0].strip():
            comments.append(lines[0].lstrip()[1:])
        lines.pop(0)
    lines = [ln for ln in lines if not ln.lstrip().startswith("#")]
    if not lines and not comments:
        raise RecordingError(f"{path}: empty file (expected a header row)")

    def delimiter(line):
        counts = {d: line.count(d) for d in (",", ";", "\t")}
        best = max(counts, key=counts.get)
        return best if counts[best] else None  # None: whitespace

    def split(line, delim):
        return next(csv.reader([line], delimiter=delim)) if delim else line.split()

    def numeric(cells):
        try:
            [float(c) for c in cells if c.strip()]
            return any(c.strip() for c in cells)
        except ValueError:
            return False

    delim = delimiter(lines[0]) if lines else None
    if not lines or numeric(split(lines[0], delim)):
        # no header row: np.savetxt writes its header as the last comment line
        head = comments[-1] if comments else ""
        d = delimiter(head)
        if lines and head.strip() and len(split(head, d)) == len(split(lines[0], delim)) \
                and not numeric(split(head, d)):
            header = split(head, d)
        elif lines:
            raise RecordingError(f"{path}: the first row holds numbers ({lines[0][:40]}), not column names: the first "
                                 "row must name the columns (time, qpos:<joint>, ctrl:<actuator>, ...)")
        else:
            raise RecordingError(f"{path}: no data rows (only a header)")
    else:
        header = split(lines.pop(0), delim)
    if not any(h.strip() for h in header):
        raise RecordingError(f"{path}: empty file (expected a header row)")
    names = [h.strip() for h in header]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise RecordingError(f"{path}: duplicated column(s) {dup}")
    data = []
    rows = csv.reader(lines, delimiter=delim) if delim else (ln.split() for ln in lines)
    for r, row in enumerate(rows, start=1):
        if not row or all(not c.strip() for c in row):
            continue  # blank line (a trailing newline)
        if len(row) != len(names):
            raise RecordingError(f"{path}: malformed CSV: data row {r} has {len(row)} values, "
                                 f"the header {len(names)} columns")
        vals = []
        for c, cell in enumerate(row):
            cell = cell.strip()
            if not cell:
                raise RecordingError(f"{path}: empty cell in column '{names[c]}' at data row {r}")
            try:
                vals.append(float(cell))
            except ValueError:
                if delim != "," and cell.count(",") == 1:
                    try:
                        vals.append(float(cell.replace(",", ".")))
                        continue
                    except ValueError:
                        pass
                raise RecordingError(f"{path}: '{cell[:20]}' in column '{names[c]}' at data row {r} "
                                     "is not a number") from None
        data.append(vals)
    if not data:
        raise RecordingError(f"{path}: no data rows (only a header)")
    arr = np.asarray(data, np.float64)
    cols = {n: arr[:, i] for i, n in enumerate(names)}
    if names[0] == "" and np.array_equal(cols[""], np.arange(len(arr))):
        del cols[""]  # a pandas index
    return cols


def _read_npz(path: str) -> dict[str, np.ndarray]:
    with np.load(path) as f:
        return {k: np.asarray(f[k], np.float64).ravel() for k in f.files}


def _read_mat(path: str) -> dict[str, np.ndarray]:
    """MATLAB: variables named like the columns (``:`` as ``__``), or the EMPS benchmark's layout."""
    from scipy.io import loadmat

    raw = loadmat(path)
    from sim2real.sysid import emps

    if emps.is_emps(raw):
        return emps.columns(raw)
    return {k.replace("__", ":"): np.asarray(v, np.float64).ravel() for k, v in raw.items() if not k.startswith("__")}


def _read_parquet(path: str) -> dict[str, np.ndarray]:
    """Apache Parquet (pyarrow): one numeric column per recording column; a null becomes NaN,
    which the validation then reports by column and row."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise RecordingError(f"{path}: reading Parquet needs pyarrow (pip install pyarrow)") from None
    table = pq.read_table(path)
    out = {}
    for name in table.column_names:
        col = table.column(name)
        if not (pa.types.is_floating(col.type) or pa.types.is_integer(col.type)):
            raise RecordingError(f"{path}: column '{name}' holds {col.type}, not numbers")
        out[name] = col.cast(pa.float64()).to_numpy(zero_copy_only=False)
    return out


def _read_mcap(path: str) -> dict[str, np.ndarray]:
    """MCAP of ROS 2 ``sensor_msgs/msg/JointState`` messages (mcap, mcap-ros2-support).

    A topic whose name contains ``command`` carries the commands: ``ctrl:<name>`` from each
    message's ``effort`` (its ``position`` where ``effort`` is empty), one name per actuator. Every
    other JointState topic carries the measurements: ``qpos:<name>``, ``qvel:<name>`` where
    ``velocity`` is filled, ``force:<name>`` where ``effort`` is (name the joints like the model's,
    efforts like its actuators). ``time`` is each message's header stamp in seconds; every topic
    must have been stamped at the same instants (one row per instant)."""
    try:
        from mcap_ros2.reader import read_ros2_messages
    except ImportError:
        raise RecordingError(f"{path}: reading MCAP needs mcap and mcap-ros2-support "
                             "(pip install mcap mcap-ros2-support)") from None
    topics: dict[str, dict] = {}
    for m in read_ros2_messages(path):
        if m.schema is None or m.schema.name != "sensor_msgs/msg/JointState":
            continue
        msg, topic = m.ros_msg, m.channel.topic
        t = topics.setdefault(topic, {"time": [], "cols": {}})
        command = "command" in topic
        n = len(t["time"])
        t["time"].append(msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec)
        fields = ([("ctrl", msg.effort if len(msg.effort) else msg.position)] if command else
                  [("qpos", msg.position), ("qvel", msg.velocity), ("force", msg.effort)])
        for kind, values in fields:
            if not len(values):
                continue
            if len(values) != len(msg.name):
                raise RecordingError(f"{path}: topic '{topic}' message {n}: {len(msg.name)} names but "
                                     f"{len(values)} values of {kind}")
            for name, v in zip(msg.name, values):
                t["cols"].setdefault(f"{kind}:{name}", []).append(float(v))
    if not topics:
        raise RecordingError(f"{path}: no sensor_msgs/msg/JointState messages")
    (first, ref), *others = topics.items()
    out = {"time": np.asarray(ref["time"])}
    for topic, t in topics.items():
        if len(t["time"]) != len(out["time"]) or not np.allclose(t["time"], out["time"], rtol=0, atol=1e-9):
            raise RecordingError(f"{path}: topic '{topic}' is not stamped at the instants of '{first}' "
                                 f"({len(t['time'])} vs {len(out['time'])} messages); resample to one clock first")
        for col, values in t["cols"].items():
            if len(values) != len(t["time"]):
                raise RecordingError(f"{path}: topic '{topic}': column '{col}' is missing in some messages")
            out[col] = np.asarray(values, np.float64)
    return out


# one reader per format; a new format is one function here (and its test)
READERS = {".csv": _read_csv, ".tsv": _read_csv, ".txt": _read_csv, ".npz": _read_npz, ".mat": _read_mat, ".parquet": _read_parquet, ".mcap": _read_mcap}


def _read_table(path: str) -> dict[str, np.ndarray]:
    ext = os.path.splitext(path)[1].lower()
    if not os.path.exists(path):
        parts = path.split(",")
        if len(parts) > 1 and all(os.path.exists(q.strip()) for q in parts):  # recordings=a.csv,b.csv
            raise RecordingError(f"{path}: file not found; for several files write a list: "
                                 f"'[{', '.join(q.strip() for q in parts)}]' (brackets, quoted for the shell)")
        raise RecordingError(f"{path}: file not found")
    if os.path.isdir(path):
        raise RecordingError(f"{path}: is a folder, not a recording file")
    if ext not in READERS:
        hint = {".xlsx": "a spreadsheet: save it as CSV", ".xls": "a spreadsheet: save it as CSV",
                ".ods": "a spreadsheet: save it as CSV", ".bag": "a ROS 1 bag: convert it to MCAP (mcap convert)",
                ".db3": "a ROS 2 SQLite bag: convert it to MCAP (ros2 bag convert)"}.get(ext)
        raise RecordingError(f"{path}: unsupported file type '{ext}' (use {', '.join(READERS)}"
                             + (f"; {hint})" if hint else ")"))
    try:
        return READERS[ext](path)
    except RecordingError:
        raise
    except Exception as e:  # unreadable file of a known type (garbage bytes, wrong encoding)
        raise RecordingError(f"{path}: cannot read as {ext[1:].upper()} ({type(e).__name__}: {e})") from None


def load(path: str, model: mujoco.MjModel) -> Recording:
    """Read and validate one recording against ``model`` (names, shapes, values, time); one whose
    logger lost samples is refused (``load_pieces`` cuts it there)."""
    return _load(path, model, cut=False)[0]


def load_pieces(path: str, model: mujoco.MjModel) -> list[Recording]:
    """``load``, with a recording whose logger lost samples (a step over ``MAX_GAP`` median steps:
    a dropped packet, a paused bag) cut there into pieces, each a recording of its own: nothing is
    interpolated over the gap (the motion in it is unknown), and each piece is simulated from its
    own first state. A piece under ``MIN_SAMPLES`` is left out; ``notes`` says where it was cut."""
    return _load(path, model, cut=True)


def _load(path: str, model: mujoco.MjModel, cut: bool) -> list[Recording]:
    cols, units = _strip_units(path, _read_table(path))
    if "time" not in cols:
        like = [c for c in cols if c.lower().startswith(("time", "stamp", "timestamp")) or c.lower() in ("t", "sec")]
        raise RecordingError(f"{path}: no 'time' column (columns: {', '.join(cols)})"
                             + (f"; if '{like[0]}' is the time, name it 'time' (in seconds)" if like else ""))
    t = cols.pop("time")
    n = len(t)
    for name, v in cols.items():
        if ":" not in name or name.split(":", 1)[0] not in KINDS:
            raise RecordingError(f"{path}: unknown column '{name}'; columns are time and "
                                 f"{', '.join(k + ':<name>' for k in KINDS)}" + _did_you_mean(name, model))
        if len(v) != n:
            raise RecordingError(f"{path}: column '{name}' has {len(v)} values, time has {n}")
    from sim2real.sysid.trajectory import ModelColumns

    mc = ModelColumns(model, path)
    # (a free or ball joint's columns name its coordinates: ``qpos:<joint>:qw``, ``qvel:<joint>:wx``)
    known = {"qpos": mc.qpos_names, "qvel": mc.dof_names, "qfrc": mc.dof_names,
             "ctrl": mc.actuators, "force": mc.actuators}
    for name in cols:
        kind, target = name.split(":", 1)
        what = _TARGET[kind]
        if kind in ("qpos", "qvel", "qfrc") and target not in known[kind] and target in mc.joints:
            coords = [c for c in known[kind] if c.startswith(target + ":")]
            raise RecordingError(f"{path}: column '{name}': joint '{target}' has several coordinates (a ball or free "
                                 f"joint); its {kind} columns are {', '.join(kind + ':' + c for c in coords)}")
        if target not in known[kind]:
            raise RecordingError(f"{path}: column '{name}' names {what} '{target}', which the model does not have "
                                 f"(model {what}s: {', '.join(str(k) for k in known[kind])})")
    _check_units(path, model, mc, units)
    if not any(c.startswith("qpos:") for c in cols):
        raise RecordingError(f"{path}: no qpos:<joint> column; at least one measured position is needed")
    missing = [a for a in known["ctrl"] if f"ctrl:{a}" not in cols]
    if missing:
        raise RecordingError(f"{path}: missing command column(s) {', '.join('ctrl:' + a for a in missing)} (every "
                             "actuator of the model needs its command; one that was unpowered: leave it out of the "
                             "model, or a motor's column of zeros)")
    # values: the first non-finite entry, by row and column
    for name, v in [("time", t)] + list(cols.items()):
        bad = ~np.isfinite(v)
        if bad.any():
            row = int(np.argmax(bad))
            raise RecordingError(f"{path}: non-finite value {v[row]} in column '{name}' at data row {row + 1}")
    if n < MIN_SAMPLES:
        raise RecordingError(f"{path}: only {n} samples; need at least {MIN_SAMPLES}")
    dt = np.diff(t)
    if (dt == 0).any():
        row = int(np.argmax(dt == 0)) + 1
        raise RecordingError(f"{path}: duplicated time {t[row]} at data rows {row} and {row + 1}")
    if (dt < 0).any():
        row = int(np.argmax(dt < 0)) + 1
        raise RecordingError(f"{path}: time goes backwards at data row {row + 1} ({t[row]} -> {t[row + 1]})")
    med = np.median(dt)
    starts = np.flatnonzero(dt > MAX_GAP * med) + 1  # the first row after each gap
    if len(starts) and not cut:
        row = int(starts[0])
        raise RecordingError(f"{path}: non-uniform sampling at data row {row + 1}: step {dt[row - 1]:.6g} s "
                             f"vs median {med:.6g} s (samples lost: cut the recording there, or resample it)")
    bounds = list(zip([0, *starts], [*starts, n]))  # [first, end) rows of each piece
    glitches = _repair_glitches(path, cols, bounds, {model.joint(j).name: int(model.jnt_type[j]) == int(
        mujoco.mjtJoint.mjJNT_HINGE) for j in range(model.njnt)})
    # a limited joint's position far outside its range is in other units (a hinge logged in
    # degrees reads +-150 against +-2.6 rad); the physics keeps a joint near its range, so a
    # sample past it by more than the range's whole span is refused
    hinge_or_slide = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    for j in range(model.njnt):
        name = model.joint(j).name
        col = cols.get(f"qpos:{name}")
        if col is None or not model.jnt_limited[j] or int(model.jnt_type[j]) not in hinge_or_slide:
            continue
        hinge = int(model.jnt_type[j]) == hinge_or_slide[0]
        lo, hi = (float(x) for x in model.jnt_range[j])
        far = _far_past(col, lo, hi)
        if far.any():
            row = int(np.argmax(far))
            # (or the model's range is the one in other units: MJCF angles are degrees unless the
            # compiler says radians, so a range written in radians reads 57x too narrow)
            d_lo, d_hi = np.degrees(lo), np.degrees(hi)
            in_rad = hinge and np.all((col >= d_lo - (d_hi - d_lo)) & (col <= d_hi + (d_hi - d_lo)))
            raise RecordingError(f"{path}: column 'qpos:{name}' reads {col[row]:.6g} at data row {row + 1}, beyond the "
                                 f"joint's range [{lo:.4g}, {hi:.4g}] by more than its span: positions must be in "
                                 + ("rad (degrees?)" if hinge else "m (millimetres?)")
                                 + (f"; or the model's range was written in radians ([{d_lo:.4g}, {d_hi:.4g}], which "
                                    "the recording fits) and read as degrees: MuJoCo reads MJCF angles in degrees "
                                    "unless <compiler angle=\"radian\"/>" if in_rad else ""))
    for a, b in bounds:  # (a velocity integrated over a gap would compare with nothing)
        _check_velocity_scale(path, model, t[a:b], {k: v[a:b] for k, v in cols.items()})
    notes = glitches + _commands_past_range(path, model, cols)
    steps = med / model.opt.timestep
    if med > MAX_PERIOD_S or steps > MAX_STEPS_PER_SAMPLE:
        raise RecordingError(f"{path}: column 'time': the samples are {med:.6g} s apart ({steps:.0f} of the model's "
                             f"{model.opt.timestep:g} s physics steps; at most {MAX_PERIOD_S:g} s and "
                             f"{MAX_STEPS_PER_SAMPLE} steps): time must be in seconds (milliseconds: divide by 1000; "
                             f"nanosecond stamps: by 1e9)")
    if len(bounds) == 1:
        return [_on_grid(Recording(path, t, cols, notes), model)]
    kept = [(a, b) for a, b in bounds if b - a >= MIN_SAMPLES]
    if not kept:
        raise RecordingError(f"{path}: samples lost at {len(starts)} places (data rows "
                             f"{', '.join(str(int(r) + 1) for r in starts[:5])}{', ...' if len(starts) > 5 else ''}), "
                             f"leaving no piece of {MIN_SAMPLES} samples or more")
    base = os.path.splitext(os.path.basename(path))[0]
    note = (f"{base}: samples lost at {len(starts)} place{'s' if len(starts) > 1 else ''} (the longest gap "
            f"{dt.max():.4g} s, {dt.max() / med:.0f} steps): cut into {len(kept)} pieces, data rows "
            + ", ".join(f"{a + 1}-{b}" for a, b in kept)
            + (f" ({n - sum(b - a for a, b in kept)} samples in pieces under {MIN_SAMPLES} left out)"
               if len(kept) < len(bounds) else "") + ", each simulated from its own first state")
    return [_on_grid(Recording(path, t[a:b], {k: v[a:b] for k, v in cols.items()}, notes + [note] if i == 0 else [],
                               rows=f"{a + 1}-{b}"), model) for i, (a, b) in enumerate(kept)]


# A unit written after a column's name, "qpos:hinge [rad]", "time (s)": read, checked, and taken off.
_UNIT = re.compile(r"^(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]$")
_SAME = {"s": "s", "sec": "s", "rad": "rad", "m": "m", "rad/s": "rad/s", "m/s": "m/s", "n": "N", "nm": "N m",
         "n m": "N m", "n*m": "N m", "n.m": "N m", "n·m": "N m", "1": "1", "-": "1", "": "1"}
# ... and the units a logger may use instead, with what makes them SI
_CONVERT = {"ms": "s: divide by 1000", "us": "s: divide by 1e6", "µs": "s: divide by 1e6", "ns": "s: divide by 1e9",
            "deg": "rad: multiply by pi/180", "°": "rad: multiply by pi/180", "degrees": "rad: multiply by pi/180",
            "mm": "m: divide by 1000", "cm": "m: divide by 100", "deg/s": "rad/s: multiply by pi/180",
            "°/s": "rad/s: multiply by pi/180", "rpm": "rad/s: multiply by pi/30", "mm/s": "m/s: divide by 1000",
            "nmm": "N m: divide by 1000", "n mm": "N m: divide by 1000", "kn": "N: multiply by 1000"}


def _strip_units(path: str, cols: dict) -> tuple[dict, dict]:
    """``{'qpos:hinge [rad]': x}`` -> ``({'qpos:hinge': x}, {'qpos:hinge': 'rad'})``."""
    out, units = {}, {}
    for name, v in cols.items():
        m = _UNIT.match(name)
        base = m.group(1).strip() if m else name
        if base in out:
            raise RecordingError(f"{path}: duplicated column '{base}' (as '{name}')")
        out[base] = v
        if m:
            units[base] = m.group(2)
    return out, units


def _check_units(path: str, model: mujoco.MjModel, mc, units: dict) -> None:
    """A unit written in a column's name must be the one the column is read in (SI, MuJoCo's):
    time in s; a hinge's position in rad, its velocity in rad/s; a slide's in m and m/s; a free
    joint's position in m, its quaternion unitless; ``force:`` and ``qfrc:`` in N or N m.
    ``ctrl:`` columns are in the actuator's own units, whatever their name says."""
    for col, unit in units.items():
        kind, _, target = col.partition(":")
        if kind == "ctrl":
            continue
        if kind == "time":
            want = {"s"}
        elif kind in ("force", "qfrc"):
            want = {"N", "N m"}
        else:
            joint, _, coord = target.partition(":")
            jt = int(model.jnt_type[model.joint(joint).id])
            if coord:
                want = {"1"} if coord.startswith("q") else {"m"} if kind == "qpos" else \
                    {"m/s"} if coord.startswith("v") else {"rad/s"}
            else:
                lin = jt == int(mujoco.mjtJoint.mjJNT_SLIDE)
                want = {("m" if lin else "rad") + ("" if kind == "qpos" else "/s")}
        u = unit.strip().lower()
        if _SAME.get(u) in want:
            continue
        fix = _CONVERT.get(u)
        raise RecordingError(f"{path}: column '{col} [{unit}]' is in {unit}; {col} is read in "
                             f"{' or '.join(sorted(want))}" + (f" (to {fix})" if fix else ""))


def _did_you_mean(name: str, model: mujoco.MjModel) -> str:
    """What an unknown column's name may have meant: ``qpos/hinge`` -> ``qpos:hinge``; a bare
    joint or actuator name -> its columns."""
    parts = re.split(r"[:/._\- ]", name, maxsplit=1)
    if len(parts) == 2 and parts[0].lower() in KINDS:
        return f" (write '{parts[0].lower()}:{parts[1]}')"
    joints = {model.joint(j).name for j in range(model.njnt)}
    acts = {model.actuator(a).name for a in range(model.nu)}
    if name in joints:
        return f" (joint '{name}': its position is 'qpos:{name}', its velocity 'qvel:{name}')"
    if name in acts:
        return f" (actuator '{name}': its command is 'ctrl:{name}', its measured force 'force:{name}')"
    return ""


GLITCH = 12.0  # a sample is a glitch when it stands this many noise levels off its neighbours' mean (``_glitches``)


def _glitches(x: np.ndarray, angle: bool) -> np.ndarray:
    """Rows of ``x [T]`` (``angle``: a hinge's position, rad) that are single-sample glitches (a
    packet read wrong, an encoder's bad count): the sample stands off its two neighbours' mean by
    ``GLITCH`` times what noise gives there (and by 1% of the column's spread, capped at a turn's
    for an angle), 4x more than any other sample within 6 does, and putting it at that mean
    leaves its neighbours' own offsets (each then half the glitch the other way) at a quarter of
    it or less. Motion does not make that pattern: a curvature moves a sample and its neighbours
    alike, an impact bends the track without the neighbours' halves, a chatter at the sample rate
    alternates, a fast transient logged at a low rate bends it at every sample near it. A
    hinge's jump by whole turns is a wrap (``trajectory.turn_jumps``), not a glitch."""
    from sim2real.sysid.trajectory import noise_std, signal_scale

    if len(x) < 9:
        return np.zeros(0, int)
    e = x[1:-1] - (x[:-2] + x[2:]) / 2  # e[k - 1]: sample k's offset from its neighbours' mean
    # (white noise: e's std is sqrt(1.5) of its; at least 1% of the spread: what the diagnosis
    # weighs a signal's error by, ``trajectory.signal_scale``, below which a glitch weighs little)
    noise = float(noise_std(x[:, None])[0])
    scale = max(GLITCH * np.sqrt(1.5) * noise, float(signal_scale(np.zeros((1, 1)), x[:, None], angles=[angle])[0]))
    k = np.flatnonzero(np.abs(e[1:-1]) > scale) + 1  # indices into e, each with both neighbours in e
    s = e[k]
    fits = (np.abs(e[k - 1] + s / 2) <= np.abs(s) / 4) & (np.abs(e[k + 1] + s / 2) <= np.abs(s) / 4)
    pad = np.pad(np.abs(e), 6)
    around = np.array([max(pad[i:i + 5].max(), pad[i + 8:i + 13].max()) for i in k])
    fits &= np.abs(s) >= 4 * around
    if angle:
        turns = np.round(np.abs(s) / (2 * np.pi))
        fits &= ~((turns >= 1) & (np.abs(np.abs(s) - 2 * np.pi * turns) < 1.0))
    return k[fits] + 1


def _repair_glitches(path: str, cols: dict, bounds, hinge: dict) -> list[str]:
    """Measured positions: each single-sample glitch (``_glitches``, within each piece between
    lost samples) set to its neighbours' mean, in place, and a note naming the column and data
    rows. (Not velocities: an impact -- a gear's teeth meeting across its backlash -- moves a
    velocity for a sample and back, which a position cannot do.) Four glitches a recording moved a
    pendulum's fitted friction by 15% and its onset speed from 0 to 0.3 rad/s
    (``new_user_probes/thirteenth_wave.txt``)."""
    notes = []
    base = os.path.splitext(os.path.basename(path))[0]
    for name, x in cols.items():
        if not name.startswith("qpos:") or name.count(":") > 1 and name.rsplit(":", 1)[1].startswith("q"):
            continue  # (a quaternion's sign may flip for a sample: trajectory.continuous_quaternions)
        rows = []
        angle = hinge.get(name[5:], False)
        for a, b in bounds:
            for r in _glitches(x[a:b], angle) + a:
                x[r] = (x[r - 1] + x[r + 1]) / 2
                rows.append(int(r) + 1)
        if rows:
            notes.append(f"{base}: {len(rows)} single-sample glitch{'es' if len(rows) > 1 else ''} in '{name}' "
                         f"(data row{'s' if len(rows) > 1 else ''} {', '.join(map(str, rows[:8]))}"
                         f"{', ...' if len(rows) > 8 else ''}) set to the mean of their neighbours")
    return notes


def _far_past(col: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``[T]`` the samples beyond the range ``[lo, hi]`` by more than its span: too far for the
    physics (a joint held near its limits, a command clamped to its range) to explain, where a
    value in other units lands (a hinge's degrees, a setpoint's millimetres)."""
    span = hi - lo
    return (col < lo - span) | (col > hi + span)


def _commands_past_range(path: str, model: mujoco.MjModel, cols: dict) -> list[str]:
    """A note per command column that lies beyond its actuator's ``ctrlrange`` by more than the
    range's span: MuJoCo clamps every command to the range, so the model is driven by the clamp,
    not by what was sent. A command in other units (a position servo's setpoint in mm or degrees
    reads 230 against +-0.3) or a ``ctrlrange`` that is not the hardware's; not refused, as a
    controller's output may be logged before the driver clamps it (the twelfth probe wave's
    linear axis, ``benchmarks/results/new_user_probes/twelfth_wave.txt``)."""
    notes = []
    base = os.path.splitext(os.path.basename(path))[0]
    for a in range(model.nu):
        col = cols.get(f"ctrl:{model.actuator(a).name}")
        if col is None or not model.actuator_ctrllimited[a]:
            continue
        lo, hi = (float(x) for x in model.actuator_ctrlrange[a])
        far = _far_past(col, lo, hi)
        if far.any():
            row = int(np.argmax(np.abs(col - (lo + hi) / 2)))
            notes.append(f"{base}: column 'ctrl:{model.actuator(a).name}' lies beyond the actuator's ctrlrange "
                         f"[{lo:.4g}, {hi:.4g}] by more than its span in {100 * far.mean():.3g}% of the rows (up to "
                         f"{col[row]:.6g}, data row {row + 1}), and MuJoCo clamps every command to the range: a "
                         "command in other units (a setpoint in mm or degrees?) or a ctrlrange that is not the "
                         "hardware's")
    return notes


def _on_grid(rec: Recording, model: mujoco.MjModel) -> Recording:
    """``rec``, resampled onto the uniform grid of its stamps where they lie off it (``_grid``)."""
    step, off = _grid(rec.time)
    return resample(rec, model, step, off) if np.abs(off).max() > UNIFORM * step else rec


def _check_velocity_scale(path: str, model: mujoco.MjModel, t: np.ndarray, cols: dict) -> None:
    """Refuse a hinge's or slide's ``qvel`` column whose displacement disagrees with its ``qpos``.

    Over windows of ``VEL_WINDOW_S`` the velocity's trapezoid integral against the time column
    and the position's change must agree within ``VEL_SCALE`` (their least-squares ratio, where it
    is off by more than ``VEL_SE`` of its standard errors; judged where the joint moves over 10
    noise stds per window and the velocity's noise is under a third of its spread). A ratio of
    57.3 is deg/s read as rad/s; 1.25, stamps 5 ms apart on samples taken every 4 ms (which, with
    positions alone, no check can see: the diagnosis then names false effects). Windows, not
    samples, so a velocity filter's lag does not count.
    """
    from sim2real.sysid.trajectory import noise_std, turn_jumps

    n = max(10, int(round(VEL_WINDOW_S / np.median(np.diff(t)))))
    edges = np.arange(0, len(t), n)
    if len(edges) < 4:
        return
    for j in range(model.njnt):
        if int(model.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE)):
            continue
        name = model.joint(j).name
        q, v = cols.get(f"qpos:{name}"), cols.get(f"qvel:{name}")
        if q is None or v is None:
            continue
        hinge = int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)
        if hinge and turn_jumps(q):
            q = np.unwrap(q)
        area = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])
        d_v, d_q = np.diff(area[edges]), np.diff(q[edges])
        # (a velocity as noisy as a third of what it measures -- an encoder's count differenced,
        # 0.9 rad/s rms on a SCARA's elbow -- integrates to displacements too uncertain to judge)
        if (np.sqrt(np.mean(d_q ** 2)) < 10 * float(noise_std(q[:, None])[0])
                or not float(noise_std(v[:, None])[0]) < np.std(v) / 3):
            continue
        k = float(np.sum(d_v * d_q) / np.sum(d_q ** 2))
        # the ratio's standard error, from the windows' scatter about it
        se = float(np.sqrt(np.sum((d_v - k * d_q) ** 2) / (len(d_q) - 1) / np.sum(d_q ** 2)))
        if abs(np.log(abs(k) + 1e-12)) > np.log(1 + VEL_SCALE) and abs(k - 1) > VEL_SE * se:
            raise RecordingError(
                f"{path}: column 'qvel:{name}' integrates over the time column to {k:.3g}x the change of "
                f"'qpos:{name}': velocities must be in {'rad/s' if hinge else 'm/s'} of the joint "
                "(deg/s read as rad/s: 57.3; rpm: 9.55; a motor's speed before its gear: the ratio), or the "
                f"time stamps are spaced {k:.3g}x the samples' true period (samples every 4 ms stamped 5 ms "
                "apart: 1.25): check the logger's rate")


def _grid(t: np.ndarray) -> tuple[float, np.ndarray]:
    """The uniform grid that fits the stamps ``t [T]``: its step (s), and how far each stamp lies
    off it ``[T]`` (s). The step is the span over the whole steps in it (each stamp's distance to
    the next, in median steps, rounded): a median of jittered steps is 1% off, which over
    hundreds of samples puts the grid steps away from the stamps; a lost sample counts as two
    steps. The grid's origin is the median one, so a first stamp taken late shifts nothing."""
    dt = np.diff(t)
    k = np.concatenate([[0], np.cumsum(np.maximum(np.round(dt / np.median(dt)), 1))])
    step = (t[-1] - t[0]) / k[-1]
    dev = t - t[0] - step * k
    return float(step), dev - np.median(dev)


def resample(rec: Recording, model: mujoco.MjModel, step: float, off: np.ndarray) -> Recording:
    """``rec`` on the uniform grid of ``step`` (s) its stamps lie ``off [T]`` (s) of (``_grid``).

    A logger's clock jitters (ROS ``joint_states``: a fifth of a step; DFKI's pendulum: one step
    6% long in 8000), and a sample taken off its instant but read as on it is off by the motion
    in between. Measured signals (positions, velocities, forces) are interpolated linearly
    between the stamps (a line through 50 rad/s^2 at 200 Hz errs by 2e-4 rad); a command is the
    one of the row nearest each instant (a loop sends it when it samples: holding the previous
    one until a late stamp would delay it by a sample now and then). A hinge angle wrapped into
    one turn (``trajectory.turn_jumps``) and an orientation quaternion are made continuous
    first, so no sample is interpolated across a wrap or a sign flip (the angle is wrapped back:
    ``ModelColumns`` unwraps it, with its note).
    """
    from sim2real.sysid.trajectory import ModelColumns, continuous_quaternions, turn_jumps

    t = rec.time
    start = t[0] - off[0]   # (the grid's instant nearest the first stamp)
    grid = start + step * np.arange(int(np.round((t[-1] - off[-1] - start) / step)) + 1)
    # (the row whose stamp is nearest each instant: rows are stamped near their own instants)
    nearest = np.clip(np.searchsorted(t, grid), 1, len(t) - 1)
    nearest -= (grid - t[nearest - 1]) < (t[nearest] - grid)
    cols = dict(rec.columns)
    mc = ModelColumns(model, rec.path)
    for qa, _ in mc.quats:
        names = [f"qpos:{mc.qpos_names[qa + i]}" for i in range(4)]
        if all(n in cols for n in names):
            q = continuous_quaternions(np.stack([cols[n] for n in names], -1), rec.path, mc.qpos_names[qa])
            cols.update({n: q[:, i] for i, n in enumerate(names)})
    hinges = {f"qpos:{mc.qpos_names[qa]}" for qa in mc.hinges}
    out = {}
    for name, v in cols.items():
        if name.startswith("ctrl:"):
            out[name] = v[nearest]
            continue
        wrapped = name in hinges and turn_jumps(v) > 0
        x = np.interp(grid, t, np.unwrap(v) if wrapped else v)
        out[name] = np.angle(np.exp(1j * x)) if wrapped else x
    return Recording(rec.path, grid, out, rec.notes + [
        f"{rec.name}: time stamps up to {np.abs(off).max() / step:.0%} of a step off the {step:.6g} s grid: "
        "resampled onto it (measurements interpolated, each command taken from the row nearest its instant)"],
        rows=rec.rows)


def check_sample_rate(recs, dt: float, reference: str) -> None:
    """Every recording must be sampled at ``dt`` (within 1%); the error names the file and ``reference``."""
    for r in recs:
        if abs(r.dt - dt) / dt > 0.01:
            raise RecordingError(f"{r.path}: sample rate {1 / r.dt:.6g} Hz differs from {reference} "
                                 f"({1 / dt:.6g} Hz); resample to one rate")


def load_all(paths, model: mujoco.MjModel, what: str = "recordings") -> list[Recording]:
    """Load several recordings and check they share one sample rate and the same columns."""
    if isinstance(paths, str):
        paths = [paths]
    if not paths:
        raise RecordingError(f"no {what} given")
    recs = [r for p in paths for r in load_pieces(p, model)]
    ref = recs[0]
    check_sample_rate(recs[1:], ref.dt, ref.path)
    for r in recs[1:]:
        if set(r.columns) != set(ref.columns):
            diff = sorted(set(r.columns) ^ set(ref.columns))
            raise RecordingError(f"{r.path}: columns differ from {ref.path} ({', '.join(diff)})")
    return recs


def save_csv(path: str, time: np.ndarray, columns: dict[str, np.ndarray]) -> None:
    """Write a recording as CSV (the generator and converters use this)."""
    names = ["time"] + list(columns)
    data = np.column_stack([time] + [columns[c] for c in columns])
    tmp = path + ".tmp"
    np.savetxt(tmp, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")
    os.replace(tmp, path)
