"""The EMPS benchmark (real hardware, bundled in ``sysid/data/emps``): conversion to recordings."""
from __future__ import annotations

import os

import numpy as np
from scipy.io import loadmat

from sim2real.sysid.recordings import RecordingError, save_csv

DATA = os.path.join(os.path.dirname(__file__), "data", "emps")
NOMINAL_XML = os.path.join(DATA, "emps_nominal.xml")
FILES = {"estimation": "DATA_EMPS.mat", "validation": "DATA_EMPS_PULSES.mat"}
# the benchmark's reference inverse-dynamics model (README): what the diagnosis should recover
REFERENCE = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "offset": -3.1648}


RECORDINGS = {k: os.path.join(DATA, f) for k, f in FILES.items()}
_VARS = ("t", "qm", "qg", "vir", "gtau")


def is_emps(raw: dict) -> bool:
    """A ``loadmat`` dict in the EMPS benchmark's own layout (read directly as a recording)."""
    return all(k in raw for k in _VARS)


def columns(d: dict) -> dict[str, np.ndarray]:
    """EMPS variables -> recording columns for ``emps_nominal.xml`` (joint ``axis``, actuator ``drive``)."""
    gtau = float(np.ravel(d["gtau"])[0])
    vir = d["vir"].ravel().astype(float)
    pulses = d["pulses_N"].ravel().astype(float) if "pulses_N" in d else np.zeros_like(vir)
    # pulses_N is 0/5 and the drive voltage vir jumps by ~5.1 V in the very sample each pulse
    # starts or ends (before the position can react): the pulses are injected into the drive's
    # voltage, i.e. a known force gtau * pulses on the load on top of the PD loop's output.
    # So the loop's own force is gtau * (vir - pulses) and the pulses are a known external force.
    cols = {"time": d["t"].ravel().astype(float), "qpos:axis": d["qm"].ravel().astype(float),
            "ctrl:drive": d["qg"].ravel().astype(float), "force:drive": gtau * (vir - pulses)}
    if "pulses_N" in d:
        cols["qfrc:axis"] = gtau * pulses
    return cols


def convert(mat_path: str, csv_path: str) -> str:
    """EMPS ``.mat`` -> recording CSV (for other tools); returns ``csv_path``."""
    d = loadmat(mat_path)
    missing = [k for k in _VARS if k not in d]
    if missing:
        raise RecordingError(f"{mat_path}: variable(s) {', '.join(missing)} missing; not an EMPS file")
    cols = columns(d)
    save_csv(csv_path, cols.pop("time"), cols)
    return csv_path


def recordings(folder: str) -> dict[str, str]:
    """Convert both bundled files into ``folder``; returns ``{'estimation': path, 'validation': path}``."""
    os.makedirs(folder, exist_ok=True)
    return {k: convert(os.path.join(DATA, f), os.path.join(folder, f.replace(".mat", ".csv"))) for k, f in FILES.items()}
