"""Readers for what ricochet writes: sweep folders (summary.csv, sweep.json, runs/<id>/),
history.csv, summary.json, VTU field files (ascii, appended raw or inline base64, zlib-compressed
or not), stability.json, case files (TOML, with a run's overrides) and the paper's reference
numbers (reference/cros2010.toml). numpy only; no meshio.

Formats: docs/outputs.md, docs/sweeps.md, docs/stability.md.
"""

import base64
import csv
import glob
import json
import math
import os
import re
import subprocess
import tomllib
import xml.etree.ElementTree as ET
import zlib

import numpy as np

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
REFERENCE_TOML = os.path.join(REPO, "reference", "cros2010.toml")


def fnum(text):
    """A number from a summary.csv field; None when empty or not a number."""
    if text is None:
        return None
    text = str(text).strip()
    if text == "":
        return None
    try:
        return float(text)
    except ValueError:
        return None


def same(a, b, rel=1e-9):
    return a is not None and b is not None and abs(a - b) <= rel * max(abs(a), abs(b))


class Run:
    """One row of a sweep's summary.csv, with lazy access to its files."""

    def __init__(self, sweep, row):
        self.sweep = sweep
        self.row = row
        self.id = row["run_id"]
        self.group = row["group"]
        self.kind = row.get("kind", "run")
        self.status = row.get("status", "")
        self.reason = row.get("reason", "")
        self.folder = os.path.join(sweep.dir, "runs", self.id)
        self._history = None
        self._summary = None

    # Swept or set values, falling back on the run's own summary.
    def get(self, key):
        return self.row.get(key, "")

    @property
    def scheme(self):
        return self.row.get("summary.scheme") or self.row.get("scheme") or ""

    @property
    def mesh(self):
        return self.row.get("summary.mesh") or self.row.get("mesh") or ""

    @property
    def dt(self):
        """The run's Δt [s]: summary's dt, else the requested time.dt."""
        v = fnum(self.row.get("dt"))
        return v if v is not None else fnum(self.row.get("time.dt"))

    @property
    def dt_requested(self):
        return self.row.get("time.dt", "")

    @property
    def friction(self):
        v = fnum(self.row.get("friction_coeff"))
        return v if v is not None else fnum(self.row.get("obstacles[0].friction"))

    def num(self, key):
        return fnum(self.row.get(key))

    @property
    def ok(self):
        return self.status == "ok"

    def history(self):
        """history.csv as a dict of numpy arrays (None if missing or empty)."""
        if self._history is None:
            self._history = read_history(os.path.join(self.folder, "history.csv"))
        return self._history

    def summary(self):
        if self._summary is None:
            path = os.path.join(self.folder, "summary.json")
            try:
                with open(path) as f:
                    self._summary = json.load(f)
            except (OSError, ValueError):
                self._summary = {}
        return self._summary

    def field_files(self):
        """[(time [s], path)] of the run's VTU files, from fields.pvd or the file names."""
        return field_files(os.path.join(self.folder, "fields"))

    def field_at(self, t, rel=0.02):
        """The VTU file whose time is nearest t (within rel·t), or None."""
        best = None
        for tt, p in self.field_files():
            d = abs(tt - t)
            if d <= rel * t + 1e-12 and (best is None or d < best[0]):
                best = (d, tt, p)
        return (best[1], best[2]) if best else None

    def label(self):
        parts = [self.mesh, scheme_name(self.scheme)]
        if self.dt is not None:
            parts.append("Δt=" + fmt_dt(self.dt) + " s")
        return " ".join(p for p in parts if p)


class Sweep:
    """A sweep folder: DIR/summary.csv, DIR/sweep.json, DIR/runs/."""

    def __init__(self, folder):
        self.dir = os.path.abspath(folder)
        self.csv = os.path.join(self.dir, "summary.csv")
        if not os.path.exists(self.csv):
            raise FileNotFoundError(f"{self.csv}: no summary.csv (not a sweep folder?)")
        try:
            with open(self.csv, newline="") as f:
                reader = csv.DictReader(f)
                self.rows = list(reader)
                self.columns = list(reader.fieldnames or [])
        except (UnicodeDecodeError, csv.Error) as e:
            raise ValueError(f"{self.csv}: not a readable CSV table ({e})") from e
        missing = [c for c in ("run_id", "group") if c not in self.columns]
        if missing:
            raise ValueError(f"{self.csv}: no column {', '.join(missing)} (not a sweep's "
                             "summary.csv; docs/sweeps.md)")
        if any(r.get("run_id") in (None, "") for r in self.rows):
            raise ValueError(f"{self.csv}: a row without run_id (a truncated or edited table?)")
        self.runs = [Run(self, r) for r in self.rows]
        try:
            with open(os.path.join(self.dir, "sweep.json")) as f:
                self.meta = json.load(f)
        except (OSError, ValueError):
            self.meta = {}
        if not isinstance(self.meta, dict):
            self.meta = {}

    @property
    def name(self):
        return self.meta.get("sweep") or os.path.basename(self.dir)

    def group(self, name, kind="run"):
        return [r for r in self.runs if r.group == name and (kind is None or r.kind == kind)]

    def find(self, group=None, mesh=None, scheme=None, dt=None, status=None, kind="run"):
        out = []
        for r in self.runs:
            if group is not None and r.group != group:
                continue
            if kind is not None and r.kind != kind:
                continue
            if mesh is not None and r.mesh != mesh:
                continue
            if scheme is not None and r.scheme != scheme:
                continue
            if dt is not None and not same(r.dt, dt, 1e-6):
                continue
            if status is not None and r.status != status:
                continue
            out.append(r)
        return out

    def version(self):
        v = self.meta.get("ricochet_version")
        if not v:
            for r in self.runs:
                if r.get("ricochet_version"):
                    return r.get("ricochet_version")
        return v or "unknown"


def read_history(path, strict=False):
    """history.csv as a dict of numpy arrays (docs/outputs.md); None when missing or without
    rows. A malformed file (a row of another length, a field that is not a number) gives None,
    or with strict a ValueError naming the file and line."""
    try:
        f = open(path, newline="")
    except OSError:
        if strict and os.path.exists(path):
            raise ValueError(f"{path}: cannot be read")
        return None
    try:
        with f:
            reader = csv.reader(f)
            header = next(reader, None)
            if not header:
                if strict:
                    raise ValueError(f"{path}: empty (no header line)")
                return None
            rows = []
            for row in reader:
                if not row:
                    continue
                if len(row) != len(header):
                    raise ValueError(f"{path}:{reader.line_num}: {len(row)} fields, the header "
                                     f"has {len(header)}")
                try:
                    rows.append([float(x) if x != "" else math.nan for x in row])
                except ValueError:
                    raise ValueError(f"{path}:{reader.line_num}: a field that is not a number")
    except (ValueError, UnicodeDecodeError, csv.Error) as e:
        if strict:
            raise ValueError(str(e)) from None
        return None
    if not rows:
        if strict:
            raise ValueError(f"{path}: no rows (a run that wrote no sample)")
        return None
    data = np.array(rows)
    return {name: data[:, i] for i, name in enumerate(header)}


def field_files(fdir):
    """[(time [s], path)] of the VTU files in a run's fields/ folder, from fields.pvd or, without
    it, from the files' TimeValue."""
    pvd = os.path.join(fdir, "fields.pvd")
    out = []
    if os.path.exists(pvd):
        try:
            root = ET.parse(pvd).getroot()
            for ds in root.iter("DataSet"):
                out.append((float(ds.get("timestep")), os.path.join(fdir, ds.get("file"))))
        except (ET.ParseError, TypeError, ValueError):
            out = []
    if not out:
        for p in sorted(glob.glob(os.path.join(fdir, "*.vtu"))):
            try:
                out.append((read_vtu(p)["time"], p))
            except Exception:  # noqa: BLE001 - an unreadable file is just skipped
                pass
    return [(t, p) for t, p in out if os.path.exists(p)]


_VTK_TYPES = {"Float64": "f8", "Float32": "f4", "Int64": "i8", "Int32": "i4", "Int16": "i2",
              "Int8": "i1", "UInt64": "u8", "UInt32": "u4", "UInt16": "u2", "UInt8": "u1"}


class _VtuDecoder:
    """The DataArrays of one VTK XML file (docs/outputs.md, fields/*.vtu): format="ascii",
    "binary" (inline base64) or "appended" (raw or base64 AppendedData), each with or without
    vtkZLibDataCompressor blocks, as VTK lays them out."""

    def __init__(self, root, appended):
        order = "<" if root.get("byte_order", "LittleEndian") == "LittleEndian" else ">"
        self.order = order
        version = root.get("version", "0.1")
        default_header = "UInt64" if version not in ("0.1", "0.2") else "UInt32"
        self.header = np.dtype(order + _VTK_TYPES[root.get("header_type", default_header)])
        self.compressed = root.get("compressor") is not None
        if root.get("compressor") not in (None, "vtkZLibDataCompressor"):
            raise ValueError(f"unsupported compressor {root.get('compressor')}")
        self.appended = appended  # (encoding, bytes) or None

    def _words(self, raw, count, at=0):
        return np.frombuffer(raw, dtype=self.header, count=count, offset=at).astype(int)

    def _from_bytes(self, raw):
        """Header and data of one array from its bytes (all decoded): the data bytes."""
        hs = self.header.itemsize
        if not self.compressed:
            n = int(self._words(raw, 1)[0])
            return raw[hs:hs + n]
        nb = int(self._words(raw, 1)[0])
        sizes = self._words(raw, nb, 3 * hs)
        at, out = (3 + nb) * hs, []
        for s in sizes:
            out.append(zlib.decompress(raw[at:at + s]))
            at += s
        return b"".join(out)

    def _inline_base64(self, text):
        text = "".join(text.split())
        hs = self.header.itemsize
        if not self.compressed:
            raw = base64.b64decode(text)
            if len(raw) == hs:  # the header encoded on its own, then the data
                n = len(base64.b64encode(raw))
                return base64.b64decode(text[n:])[:int(self._words(raw, 1)[0])]
            return self._from_bytes(raw)
        first = 4 * ((3 * hs + 2) // 3)
        nb = int(self._words(base64.b64decode(text[:first])[:3 * hs], 1)[0])
        hlen = 4 * (((3 + nb) * hs + 2) // 3)
        head = base64.b64decode(text[:hlen])
        data = base64.b64decode(text[hlen:])
        return self._from_bytes(head + data)

    def _appended(self, offset):
        encoding, blob = self.appended
        hs = self.header.itemsize
        if encoding == "raw":
            if not self.compressed:
                n = int(self._words(blob, 1, offset)[0])
                return blob[offset + hs:offset + hs + n]
            nb = int(self._words(blob, 1, offset)[0])
            total = (3 + nb) * hs + int(np.sum(self._words(blob, nb, offset + 3 * hs)))
            return self._from_bytes(blob[offset:offset + total])
        text = blob[offset:].decode("ascii")
        end = len(text)
        for stop in ("<", "\n"):
            k = text.find(stop)
            end = min(end, k) if k >= 0 else end
        return self._inline_base64(text[:end])

    def values(self, da):
        kind = da.get("type")
        fmt = da.get("format", "ascii")
        if fmt == "ascii":
            return np.array(da.text.split(), dtype=float) if da.text else np.zeros(0)
        if fmt == "binary":
            raw = self._inline_base64(da.text or "")
        elif fmt == "appended":
            raw = self._appended(int(da.get("offset")))
        else:
            raise ValueError(f"unknown DataArray format {fmt}")
        return np.frombuffer(raw, dtype=np.dtype(self.order + _VTK_TYPES[kind])).astype(float)


def _parse_vtu(path):
    """(XML root, appended data (encoding, bytes) or None) of a VTU file; raw AppendedData is
    cut off before parsing (it is not XML)."""
    with open(path, "rb") as f:
        blob = f.read()
    at = blob.find(b"<AppendedData")
    if at < 0:
        return ET.fromstring(blob), None
    tag_end = blob.index(b">", at)
    encoding = re.search(rb'encoding="([^"]*)"', blob[at:tag_end + 1])
    encoding = encoding.group(1).decode() if encoding else "raw"
    start = blob.index(b"_", tag_end) + 1
    end = blob.rfind(b"</AppendedData>")
    root = ET.fromstring(blob[:at] + b"</VTKFile>")
    return root, (encoding, blob[start:end])


def read_vtu(path):
    """A VTK XML UnstructuredGrid as written by ricochet (docs/outputs.md), in any of its
    field formats: {time, points (n,2) deformed, displacement (n,2), cells [list of index
    arrays], cell_data {name: array}, point_data {name: array}}, and for a 3D file (tetrahedra,
    hexahedra) points3 (n,3) deformed; arrays of several components are (tuples, components)."""
    root, appended = _parse_vtu(path)
    dec = _VtuDecoder(root, appended)
    out = {"time": math.nan, "cell_data": {}, "point_data": {}}
    for fd in root.iter("FieldData"):
        for da in fd.iter("DataArray"):
            if da.get("Name") == "TimeValue":
                out["time"] = float(dec.values(da)[0])
    piece = next(root.iter("Piece"))

    def arrays(section, into):
        for da in (list(section) if section is not None else []):
            a = dec.values(da)
            nc = int(da.get("NumberOfComponents", "1"))
            into[da.get("Name")] = a.reshape(-1, nc) if nc > 1 else a

    arrays(piece.find("PointData"), out["point_data"])
    arrays(piece.find("CellData"), out["cell_data"])
    pts = dec.values(piece.find("Points").find("DataArray")).reshape(-1, 3)
    out["points"] = pts[:, :2]
    cells = {da.get("Name"): da for da in piece.find("Cells")}
    conn = dec.values(cells["connectivity"]).astype(int)
    offs = dec.values(cells["offsets"]).astype(int)
    starts = np.concatenate([[0], offs[:-1]])
    out["cells"] = [conn[a:b] for a, b in zip(starts, offs)]
    # 3D files (VTK_TETRA 10, VTK_HEXAHEDRON 12): the full coordinates too.
    if "types" in cells and np.isin(dec.values(cells["types"]).astype(int), (10, 12)).any():
        out["points3"] = pts
    disp = out["point_data"].get("displacement")
    out["displacement"] = disp[:, :2] if disp is not None else np.zeros_like(out["points"])
    return out


def resolve_case_file(case_file):
    """The case file a run names in summary.json (`case_file`, as given on its command line):
    absolute, else relative to the repository, else to the current folder; None if not found."""
    if not case_file:
        return None
    cands = [case_file] if os.path.isabs(case_file) else \
        [os.path.join(REPO, case_file), os.path.abspath(case_file)]
    return next((p for p in cands if os.path.isfile(p)), None)


def _override_path(key):
    """'obstacles[1].center' -> ['obstacles', 1, 'center']."""
    out = []
    for part in key.split("."):
        m = re.fullmatch(r"([^\[\]]+)((?:\[\d+\])*)", part.strip().strip('"'))
        if not m:
            return None
        out.append(m.group(1))
        out += [int(i) for i in re.findall(r"\[(\d+)\]", m.group(2))]
    return out


def read_case(path, overrides=()):
    """A case TOML (docs/case-format.md) with the run's `--set KEY=VALUE` overrides applied
    (summary.json `overrides`). An override that does not fit the file is left out."""
    with open(path, "rb") as f:
        case = tomllib.load(f)
    for item in overrides or []:
        if "=" not in item:
            continue
        key, text = item.split("=", 1)
        try:
            value = tomllib.loads("v = " + text)["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        keys = _override_path(key)
        if not keys:
            continue
        obj = case
        try:
            for k in keys[:-1]:
                if isinstance(k, str) and k not in obj:
                    obj[k] = {}
                obj = obj[k]
            obj[keys[-1]] = value
        except (KeyError, IndexError, TypeError):
            continue
    return case


def read_reference(path=REFERENCE_TOML):
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError):
        return {}


def find_stability_files(paths):
    """stability.json files: each path is a file, or a folder searched recursively."""
    out = []
    for p in paths:
        if os.path.isfile(p):
            out.append(os.path.abspath(p))
        elif os.path.isdir(p):
            for root, dirs, files in os.walk(p):
                dirs.sort()
                if "stability.json" in files:
                    out.append(os.path.abspath(os.path.join(root, "stability.json")))
    seen, uniq = set(), []
    for p in out:
        if p not in seen:
            seen.add(p)
            uniq.append(p)
    return uniq


def read_stability(path):
    with open(path) as f:
        d = json.load(f)
    d["_path"] = path
    return d


def show_path(p):
    """A path relative to the repository when inside it, else absolute."""
    p = os.path.abspath(p)
    return os.path.relpath(p, REPO) if p.startswith(REPO + os.sep) else p


def git_commit(path):
    """(short hash, dirty flag) of the git work tree holding path, or (None, None)."""
    try:
        h = subprocess.run(["git", "-C", path, "rev-parse", "--short", "HEAD"],
                           capture_output=True, text=True, timeout=10)
        if h.returncode != 0:
            return None, None
        s = subprocess.run(["git", "-C", path, "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True, timeout=20)
        return h.stdout.strip(), bool(s.stdout.strip())
    except (OSError, subprocess.SubprocessError):
        return None, None


SCHEME_NAMES = {
    "semi_explicit": "semi-explicit",
    "implicit": "implicit",
    "explicit_penalty": "explicit penalty",
    "explicit": "explicit",
}


def scheme_name(s):
    return SCHEME_NAMES.get(s, s)


def fmt_dt(dt):
    """1e-05 -> '1e-5', 8.25e-06 -> '8.25e-6', 0.003 -> '0.003'."""
    if dt is None:
        return "–"
    if dt == 0 or 1e-3 <= abs(dt) < 1e3:
        return f"{dt:.3g}"
    m, e = f"{dt:.2e}".split("e")
    m = m.rstrip("0").rstrip(".")
    return f"{m}e{int(e)}"


def fmt_g(x, digits=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if x == 0:
        return "0"
    ax = abs(x)
    if 1e-3 <= ax < 1e5:
        if ax >= 10 ** (digits - 1):
            return f"{x:.0f}"
        return f"{x:.{digits}g}"
    m, e = f"{x:.{digits - 1}e}".split("e")
    return f"{m}e{int(e)}"
