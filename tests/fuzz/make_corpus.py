#!/usr/bin/python3
"""Seed corpora and dictionaries of the fuzz targets, made from the repository's own files.

    tests/fuzz/make_corpus.py OUT_DIR [BUILD_DIR]

writes OUT_DIR/seeds/{case,gmsh,csv,gates}/ (one file per seed) and OUT_DIR/{case,gmsh,csv,
gates}.dict (libFuzzer -dict= files). Nothing of it is committed: ci/fuzz makes it afresh in
build-fuzz/. Sources (docs/reliability.md, Fuzzing):
- case: every case file under cases/ (a file with a [meshes] table; full-line comments
  dropped, generated meshes coarsened to at most 4 cells across; a variant with integral
  numbers written as integers), and for every sweep file under cases/ the runs it would start, as their base case
  with the sweep's `set` and the first value of each `cross` key as leading "--set KEY=VALUE" lines
  (sweep files are not cases: read_case never sees one), and a case on a Gmsh mesh of
  tests/data;
- gmsh: tests/data/*.msh;
- csv: a few hand-made tables (quotes, CRLF, byte-order mark, nan/inf), and the summary.csv and
  history.csv files that ci/test's fast-tier studies wrote under BUILD_DIR/studies-fast (default
  build/), if any;
- gates: every gate file of a study (cases/*/gates*.toml; and the integer variant, as for cases),
  and each one followed by "%%csv" and the summary.csv of the study's sweep it gates in the fast
  tier (docs/studies.md), when that exists.
"""
import pathlib
import re
import sys
import tomllib

ROOT = pathlib.Path(__file__).resolve().parents[2]


def strip_comments(text):
    return "".join(l for l in text.splitlines(keepends=True) if not l.lstrip().startswith("#") and l.strip())


def coarse(text):
    """The case with every generated mesh at most 4 cells across (nx, ny, nz, n): the readers' logic
    is the same, and an input that builds a mesh of 400 or 50000 cells slows the fuzzer down
    100 to 10000 times (the sweeps' finest meshes take seconds under the sanitizers)."""
    return re.sub(r"^(\s*(?:nx|ny|nz|n)\s*=\s*)(\d+)", lambda m: m.group(1) + str(min(int(m.group(2)), 4)),
                  text, flags=re.M)


def integral(text):
    """The text with every integral float literal written as an integer (2.0e11 -> 200000000000,
    8000.0 -> 8000): a variant seed whose numbers libFuzzer's integer mutations (ChangeASCIIInt)
    can grow past 2^53 and 2^63, where TOML integers stop being doubles or stop being valid."""
    def repl(m):
        lit = m.group(0)
        if "." not in lit and "e" not in lit.lower():
            return lit
        try:
            x = float(lit)
        except ValueError:
            return lit
        return str(int(x)) if x.is_integer() and abs(x) < 1e18 else lit
    return re.sub(r"(?<![\w.\"-])-?\d+(?:\.\d+)?(?:[eE][+-]?\d+)?(?![\w.\"])", repl, text)


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f'"{k}" = {toml_value(x)}' for k, x in v.items()) + " }"
    raise TypeError(v)


def keys_of(node, out):
    """Every key and string value of a parsed TOML document, recursively."""
    if isinstance(node, dict):
        for k, v in node.items():
            out["keys"].add(k)
            if isinstance(v, dict):
                out["tables"].add(k)
            elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
                out["arrays"].add(k)
            keys_of(v, out)
    elif isinstance(node, list):
        for v in node:
            keys_of(v, out)
    elif isinstance(node, str) and len(node) <= 40:
        out["words"].add(node)


def dict_line(s):
    esc = "".join(c if 32 <= ord(c) < 127 and c not in '"\\' else "\\x%02X" % ord(c) for c in s)
    return f'"{esc}"\n'


def write_dict(path, entries):
    path.write_text("".join(dict_line(e) for e in sorted(set(entries)) if e))


def main():
    out = pathlib.Path(sys.argv[1]).resolve()
    build = pathlib.Path(sys.argv[2]).resolve() if len(sys.argv) > 2 else ROOT / "build"
    seeds = {t: out / "seeds" / t for t in ("case", "gmsh", "csv", "gates")}
    for d in seeds.values():
        d.mkdir(parents=True, exist_ok=True)
        for f in d.iterdir():
            f.unlink()
    count = {t: 0 for t in seeds}

    def seed(target, name, text):
        name = re.sub(r"[^A-Za-z0-9_.-]", "_", name)
        (seeds[target] / name).write_bytes(text.encode() if isinstance(text, str) else text)
        count[target] += 1

    # ---- case ----
    case_words = {"keys": set(), "tables": set(), "arrays": set(), "words": set()}
    cases, sweeps = {}, []
    for f in sorted((ROOT / "cases").rglob("*.toml")):
        doc = tomllib.loads(f.read_text())
        keys_of(doc, case_words)
        if "meshes" in doc:
            cases[f] = f.read_text()
        else:
            sweeps.append((f, doc))
    cases = {f: coarse(strip_comments(text)) for f, text in cases.items()}
    for f, text in cases.items():
        seed("case", "case-" + str(f.relative_to(ROOT / "cases")), text)
        if integral(text) != text:
            seed("case", "case-int-" + str(f.relative_to(ROOT / "cases")), integral(text))
    for f, doc in sweeps:
        rel = str(f.relative_to(ROOT / "cases"))
        top_set = doc.get("set", {})
        for i, g in enumerate(doc.get("group", [{}])):
            base = f.parent / g.get("base", doc.get("base", ""))
            if base not in cases:
                continue
            sets = dict(top_set)
            sets.update(g.get("set", {}))
            for k, values in g.get("cross", {}).items():
                sets[k] = values[0] if isinstance(values, list) and values else values
            for k, v in sets.items():  # coarse() for the overrides too
                if k.split(".")[-1] in ("nx", "ny", "n") and isinstance(v, int):
                    sets[k] = min(v, 4)
            lines = "".join(f"--set {k}={toml_value(v)}\n" for k, v in sets.items())
            seed("case", f"sweep-{rel}-{i}", lines + cases[base])
    seed("case", "gmsh-mesh.toml", """--set time.end=2e-6
name = "on_gmsh"
mesh = "m"
scheme = "semi_explicit"
[meshes.m]
file = "gmsh_quad_2x1_v41.msh"
scale = 0.01
[[bodies]]
name = "plate"
velocity = [0.0, -1.0]
[bodies.material]
young = 2e11
poisson = 0.3
density = 7800.0
[[obstacles]]
name = "ground"
type = "line"
point = [0.0, -0.001]
normal = [0.0, 1.0]
friction = 0.2
[time]
end = 1e-5
dt = "auto"
[[output.probes]]
name = "corner"
node_set = "bottom"
""")
    # Keys from the case-format tables too (some appear in no case file).
    doc_keys = re.findall(r"^\| `([A-Za-z_][A-Za-z0-9_.]*)`", (ROOT / "docs/case-format.md").read_text(), re.M)
    case_dict = set(case_words["keys"]) | set(doc_keys)
    case_dict |= {f"[{t}]" for t in case_words["tables"]} | {f"[[{t}]]" for t in case_words["arrays"]}
    case_dict |= {f'"{w}"' for w in case_words["words"]}
    case_dict |= {"--set ", " = ", "[0]", ".", "=", "\n", "auto", "true", "false", "1e-6", "inf", "nan",
                  "9007199254740993", "9223372036854775807", "1e-300", "1e300", "1e308", "-0.0", "100000",
                  "gmsh_quad_2x1_v22.msh", "gmsh_quad_2x1_v41.msh", "gmsh_mixed_v41.msh", "/dev/zero", "/dev/stdin"}
    write_dict(out / "case.dict", case_dict)

    # ---- gmsh ----
    for f in sorted((ROOT / "tests/data").glob("*.msh")):
        seed("gmsh", f.name, f.read_bytes())
    gmsh_dict = {f"${s}" for s in ("MeshFormat", "PhysicalNames", "Entities", "Nodes", "Elements",
                                   "NodeData", "Comments")}
    gmsh_dict |= {"$End" + s[1:] for s in gmsh_dict}
    gmsh_dict |= {"2.2 0 8", "4.1 0 8", "2.2", "4.1", " 0 ", " 1 ", " 2 ", " 3 ", " 15 ", "\n", '"', "-1",
                  "1e308", "9223372036854775807", "2147483648"}
    write_dict(out / "gmsh.dict", gmsh_dict)

    # ---- csv ----
    seed("csv", "hand-quotes.csv", 'run,"a,b","say ""hi"""\nx,1,"two\nlines"\ny,,"""\n')
    seed("csv", "hand-crlf-bom.csv", "\ufeffname,value\r\nalpha,1e-06\r\n\r\nbeta,-inf\r\ngamma,nan\r")
    seed("csv", "hand-numbers.csv", "x,y,z\n 0.000001 ,+2.5,1e999\n-3,inf,\t-0\t\n")
    fast = build / "studies-fast"
    csvs = sorted(fast.glob("*/*/summary.csv")) + sorted(fast.glob("*/*/runs/*/*/history.csv"))[:6]
    for f in csvs:
        lines = f.read_text().splitlines(keepends=True)[:40]  # a few rows are enough
        seed("csv", str(f.relative_to(build)), "".join(lines))
    write_dict(out / "csv.dict", {",", '"', '""', "\r\n", "\n", "\r", "\ufeff", "nan", "inf", "-inf",
                                  "1e-06", "0.000001", "+", "e308"})

    # ---- gates ----
    gate_words = {"keys": set(), "tables": set(), "arrays": set(), "words": set()}
    summaries = {}
    for study in sorted((ROOT / "cases").glob("*/study.toml")):
        for entry in tomllib.loads(study.read_text()).get("sweep", []):
            if "gates" in entry and "fast" in entry.get("tier", ["fast", "full"]):
                gates = (study.parent / entry["gates"]).relative_to(ROOT)
                summaries[str(gates)] = fast / study.parent.name / entry["name"] / "summary.csv"
    for f in sorted((ROOT / "cases").glob("*/gates*.toml")):
        text = f.read_text()
        keys_of(tomllib.loads(text), gate_words)
        name = f.parent.name + "-" + f.name
        seed("gates", name, strip_comments(text))
        if integral(strip_comments(text)) != strip_comments(text):
            seed("gates", "int-" + name, integral(strip_comments(text)))
        s = summaries.get(str(f.relative_to(ROOT)))
        if s and s.is_file():
            seed("gates", f.parent.name + "-" + f.stem + "-with-table.toml", strip_comments(text) + "%%csv\n" + s.read_text())
    gates_dict = set(gate_words["keys"]) | {f'"{w}"' for w in gate_words["words"]}
    gates_dict |= {"[[gate]]", "kind", '"max"', '"min"', '"near"', '"ratio"', '"count"', '"pattern"',
                   "%%csv\n", "include", "gates_common.toml", "9223372036854775807", "1e308", "nan", "inf"}
    write_dict(out / "gates.dict", gates_dict)

    print("make_corpus: " + ", ".join(f"{t} {n} seeds" for t, n in count.items()) + f" in {out / 'seeds'}")


if __name__ == "__main__":
    main()
