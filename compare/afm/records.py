"""AFM force curves in SI units: the JPK reader (through ``afmformats``, the ``afm`` extra) and CSV exports.

A :class:`Curve` holds one force curve as the instrument recorded it: ``time`` (s), ``height`` (m: the
measured probe height above the sample's support, decreasing while the probe approaches), ``force`` (N,
cantilever deflection times the spring constant, baseline NOT removed) and ``segment`` (an integer per
sample; ``segment_names`` name them, e.g. ``("pause", "approach", "hold", "retract")`` for a JPK
stress-relaxation curve: a pause at constant height, the approach at constant speed, the hold at constant
height, the retract). ``spring_constant`` (N/m) and ``sensitivity`` (m/V) come from the file.

CSV files (what labs export): one header line of column names with units in parentheses or brackets, e.g.
``time (s), height (um), force (nN), segment``; lines starting with ``#`` before it may carry
``# spring constant: 1.0677 N/m`` and ``# sensitivity: 110.28 nm/V``. Recognised columns:

* time: ``time``/``t`` (s, ms);
* height: ``height``, ``height (measured)``, ``piezo``, ``z`` (m, um, nm);
* force ``force`` (N, nN, pN), or ``deflection`` (m, um, nm; times the spring constant) or ``deflection``
  in V (times the sensitivity, then the spring constant: both needed in the header);
* ``segment`` (integers; absent: one segment) and ``curve`` (several curves in one file: one Curve each).

A file may be gzip-compressed (``.csv.gz``).
"""

from __future__ import annotations

import gzip
import io
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from tissuemech.reduced.validation import InputError

__all__ = ["Curve", "read_jpk", "read_csv", "write_csv", "JPK_SEGMENTS", "binned", "recalibrated"]

JPK_SEGMENTS = ("pause", "approach", "hold", "retract")

_SCALE = {
    "s": 1.0,
    "ms": 1e-3,
    "m": 1.0,
    "mm": 1e-3,
    "um": 1e-6,
    "µm": 1e-6,
    "μm": 1e-6,
    "nm": 1e-9,
    "n": 1.0,
    "mn": 1e-3,
    "un": 1e-6,
    "µn": 1e-6,
    "nn": 1e-9,
    "pn": 1e-12,
    "v": 1.0,
    "mv": 1e-3,
    "n/m": 1.0,
    "mn/m": 1e-3,
    "pn/nm": 1e-3,
    "m/v": 1.0,
    "nm/v": 1e-9,
    "um/v": 1e-6,
    "µm/v": 1e-6,
}
_KIND = {"s": "time", "ms": "time", "v": "voltage", "mv": "voltage"}
_KIND.update({u: "length" for u in ("m", "mm", "um", "µm", "μm", "nm")})
_KIND.update({u: "force" for u in ("n", "mn", "un", "µn", "nn", "pn")})


@dataclass
class Curve:
    """One AFM force curve (module doc): arrays of equal length and the cantilever calibration."""

    time: np.ndarray
    height: np.ndarray
    force: np.ndarray
    segment: np.ndarray
    spring_constant: float
    sensitivity: float | None = None
    segment_names: tuple[str, ...] = JPK_SEGMENTS
    name: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.time = np.asarray(self.time, dtype=float)
        self.height = np.asarray(self.height, dtype=float)
        self.force = np.asarray(self.force, dtype=float)
        self.segment = np.asarray(self.segment, dtype=int)
        n = self.time.size
        for what, arr in (("height (m)", self.height), ("force (N)", self.force), ("segment", self.segment)):
            if arr.shape != (n,):
                raise InputError(f"curve {self.name!r}: {what} needs one value per time sample ({n}); got {arr.size}")
        if n < 4 or not (np.all(np.isfinite(self.time)) and np.all(np.isfinite(self.height))):
            raise InputError(f"curve {self.name!r}: time (s) and height (m) need >= 4 finite samples")
        if np.any(np.diff(self.time) <= 0):
            raise InputError(f"curve {self.name!r}: time (s) must be strictly increasing")
        if not (np.isfinite(self.spring_constant) and self.spring_constant > 0):
            raise InputError(
                f"spring_constant (of the cantilever) must be positive (in N/m); got {self.spring_constant}"
            )

    def part(self, name: str) -> np.ndarray:
        """Boolean mask of the samples of the segment called ``name`` (e.g. ``"hold"``)."""
        if name not in self.segment_names:
            raise InputError(f"curve {self.name!r} has no segment {name!r}; its segments: {self.segment_names}")
        return self.segment == self.segment_names.index(name)

    @property
    def deflection(self) -> np.ndarray:
        """Cantilever deflection (m) = force / spring constant (with the force's baseline offset)."""
        return self.force / self.spring_constant


def read_jpk(path: str | Path) -> list[Curve]:
    """The force curves of a JPK file (``.jpk-force``; or every ``*.jpk-force`` in a folder or a ``.zip``),
    read by ``afmformats`` (``pip install tissuemech[afm]``). Force (N), height = "height (measured)" (m)."""
    try:
        import afmformats
    except ImportError:  # pragma: no cover - exercised only without the extra
        raise ImportError("reading JPK files needs afmformats: pip install 'tissuemech[afm]'") from None
    p = Path(path)
    if p.suffix == ".zip":
        import tempfile
        import zipfile

        with tempfile.TemporaryDirectory() as tmp, zipfile.ZipFile(p) as z:
            z.extractall(tmp)
            return read_jpk(tmp)
    files = sorted(p.rglob("*.jpk-force")) if p.is_dir() else [p]
    if not files:
        raise FileNotFoundError(f"no .jpk-force file in {p}")
    out = []
    for f in files:
        for di in afmformats.load_data(f):
            md = dict(di.metadata)
            out.append(
                Curve(
                    time=np.asarray(di["time"]),
                    height=np.asarray(di["height (measured)"]),
                    force=np.asarray(di["force"]),
                    segment=np.asarray(di["segment"]),
                    spring_constant=float(md["spring constant"]),
                    sensitivity=float(md["sensitivity"]) if "sensitivity" in md else None,
                    segment_names=JPK_SEGMENTS
                    if md.get("imaging mode") == "stress-relaxation"
                    else ("approach", "retract"),
                    name=f.stem,
                    metadata={k: v for k, v in md.items() if isinstance(v, (int, float, str))},
                )
            )
    return out


def _unit(header: str) -> tuple[str, str]:
    """('name', 'unit') from 'name (unit)' / 'name [unit]' / 'name_unit'."""
    h = header.strip().strip('"')
    m = re.match(r"^(.*?)\s*[\(\[]\s*([^\)\]]*)\s*[\)\]]\s*$", h)
    if m:
        return m.group(1).strip().lower(), m.group(2).strip().lower()
    m = re.match(r"^(.*?)_(s|ms|m|mm|um|nm|n|nn|pn|v|mv)$", h.lower())
    if m:
        return m.group(1), m.group(2)
    return h.lower(), ""


def _value_with_unit(text: str, what: str, unit_si: str) -> float:
    m = re.match(r"^\s*([-+0-9.eE]+)\s*(\S*)\s*$", text)
    if not m:
        raise InputError(f"CSV header: cannot read {what} from {text!r} (expected e.g. '1.07 {unit_si}')")
    u = (m.group(2) or unit_si).lower()
    if u not in _SCALE:
        raise InputError(f"CSV header: unknown unit {u!r} for the {what} (use {unit_si})")
    return float(m.group(1)) * _SCALE[u]


def _open_text(path: Path) -> str:
    raw = path.read_bytes()
    if raw[:2] == b"\x1f\x8b":
        raw = gzip.decompress(raw)
    return raw.decode("utf-8")


def read_csv(
    path: str | Path, *, spring_constant: float | None = None, sensitivity: float | None = None
) -> list[Curve]:
    """The curves of a CSV export (module doc: columns and units), one Curve per value of a ``curve`` column.

    ``spring_constant`` (N/m) and ``sensitivity`` (m/V) override the header's. Raises InputError for a
    missing column, an unknown unit, or a deflection without the calibration needed to make it a force."""
    p = Path(path)
    text = _open_text(p)
    meta: dict[str, str] = {}
    lines = text.splitlines()
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        m = re.match(r"#\s*([^:=]+?)\s*[:=]\s*(.+)$", lines[i])
        if m:
            meta[m.group(1).strip().lower()] = m.group(2).strip()
        i += 1
    if i >= len(lines):
        raise InputError(f"{p}: no header line with column names (e.g. 'time (s), height (um), force (nN)')")
    headers = [_unit(h) for h in lines[i].split(",")]
    data = np.loadtxt(io.StringIO("\n".join(lines[i + 1 :])), delimiter=",", ndmin=2)
    if data.shape[1] != len(headers):
        raise InputError(f"{p}: {len(headers)} column names but {data.shape[1]} columns of numbers")
    k = spring_constant
    if k is None and "spring constant" in meta:
        k = _value_with_unit(meta["spring constant"], "spring constant", "N/m")
    sens = sensitivity
    if sens is None and "sensitivity" in meta:
        sens = _value_with_unit(meta["sensitivity"], "sensitivity", "m/V")

    def column(names: tuple[str, ...], kinds: tuple[str, ...], default_unit: str) -> tuple[np.ndarray, str] | None:
        for j, (n, u) in enumerate(headers):
            if n in names or any(n.startswith(x + " ") for x in names):
                u = u or default_unit
                if u not in _SCALE or _KIND.get(u) not in kinds:
                    raise InputError(f"{p}: column {n!r} has unit {u!r}; expected one of {kinds} (e.g. {default_unit})")
                return data[:, j] * _SCALE[u], _KIND[u]
        return None

    t = column(("time", "t"), ("time",), "s")
    h = column(("height", "height (measured)", "piezo", "z", "height measured"), ("length",), "m")
    if t is None or h is None:
        raise InputError(f"{p}: needs a time column (s) and a height column (m); got {[n for n, _ in headers]}")
    f = column(("force",), ("force",), "N")
    if f is not None:
        force = f[0]
    else:
        d = column(("deflection", "vdeflection"), ("length", "voltage"), "m")
        if d is None:
            raise InputError(f"{p}: needs a force column (N) or a deflection column (m or V)")
        if k is None:
            raise InputError(f"{p}: a deflection column needs the spring constant (N/m): header or spring_constant=")
        defl, kind = d
        if kind == "voltage":
            if sens is None:
                raise InputError(f"{p}: a deflection in V needs the sensitivity (m/V): header or sensitivity=")
            defl = defl * sens
        force = defl * k
    if k is None:
        raise InputError(f"{p}: the spring constant (N/m) is needed: '# spring constant: 1.07 N/m' or spring_constant=")
    names = [n for n, _ in headers]
    seg = data[:, names.index("segment")].astype(int) if "segment" in names else np.zeros(len(data), int)
    seg_names = (
        tuple(meta["segments"].split()) if "segments" in meta else (JPK_SEGMENTS if "segment" in names else ("all",))
    )
    cid = data[:, names.index("curve")].astype(int) if "curve" in names else np.zeros(len(data), int)
    out = []
    for c in np.unique(cid):
        m = cid == c
        out.append(
            Curve(t[0][m], h[0][m], force[m], seg[m], float(k), sens, seg_names, name=f"{p.stem.split('.')[0]}-{c}")
        )
    return out


def write_csv(curves: list[Curve], path: str | Path, *, note: str = "") -> None:
    """Write curves as one CSV (``curve, segment, time (s), height (m), force (N)``, calibration in the header;
    gzip-compressed when ``path`` ends in ``.gz``), readable by :func:`read_csv`."""
    if not curves:
        raise InputError("write_csv needs at least one curve")
    k = {c.spring_constant for c in curves}
    if len(k) != 1:
        raise InputError("write_csv: the curves of one file must share the spring constant (N/m)")
    lines = [f"# {line}" for line in note.splitlines()]
    lines.append(f"# spring constant: {curves[0].spring_constant!r} N/m")
    if curves[0].sensitivity is not None:
        lines.append(f"# sensitivity: {curves[0].sensitivity!r} m/V")
    lines.append("# segments: " + " ".join(curves[0].segment_names))
    lines.append("curve,segment,time (s),height (m),force (N)")
    for j, c in enumerate(curves):
        for s, tt, hh, ff in zip(c.segment, c.time, c.height, c.force):
            lines.append(f"{j},{s},{tt:.7g},{hh:.9g},{ff:.6g}")
    text = "\n".join(lines) + "\n"
    p = Path(path)
    if p.suffix == ".gz":
        p.write_bytes(gzip.compress(text.encode(), mtime=0))
    else:
        p.write_text(text)


def binned(curve: Curve, factors: dict[str, int]) -> Curve:
    """A lighter copy: in each segment named in ``factors``, consecutive samples averaged in groups of that size
    (time, height and force alike; a trailing partial group dropped). Averaging keeps the mean signal and lowers
    the white noise by sqrt(group size); used to make the shipped extract of the real records."""
    parts = []
    for code, name in enumerate(curve.segment_names):
        m = curve.segment == code
        n = factors.get(name, 1)
        idx = np.flatnonzero(m)
        g = idx.size // n
        if g == 0:
            continue
        sl = idx[: g * n]
        parts.append(
            tuple(a[sl].reshape(g, n).mean(axis=1) for a in (curve.time, curve.height, curve.force))
            + (np.full(g, code),)
        )
    t, h, f, s = (np.concatenate(v) for v in zip(*parts))
    return Curve(
        t, h, f, s, curve.spring_constant, curve.sensitivity, curve.segment_names, curve.name, dict(curve.metadata)
    )


def recalibrated(curve: Curve, *, spring_constant: float | None = None, sensitivity: float | None = None) -> Curve:
    """A copy with another cantilever calibration: force = deflection voltage x sensitivity (m/V) x spring
    constant (N/m), so the force is rescaled by k_new / k_old and s_new / s_old (the latter needs the curve's own
    sensitivity). None keeps the file's value."""
    f = curve.force.copy()
    k, s = curve.spring_constant, curve.sensitivity
    if spring_constant is not None:
        if not (np.isfinite(spring_constant) and spring_constant > 0):
            raise InputError(f"spring_constant must be positive (in N/m); got {spring_constant}")
        f *= spring_constant / k
        k = float(spring_constant)
    if sensitivity is not None:
        if not (np.isfinite(sensitivity) and sensitivity > 0):
            raise InputError(f"sensitivity must be positive (in m/V); got {sensitivity}")
        if s is None:
            raise InputError(f"curve {curve.name!r} has no sensitivity (m/V) of its own to rescale the force from")
        f *= sensitivity / s
        s = float(sensitivity)
    return Curve(
        curve.time, curve.height, f, curve.segment, k, s, curve.segment_names, curve.name, dict(curve.metadata)
    )
