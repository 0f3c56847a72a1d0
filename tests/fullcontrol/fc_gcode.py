"""Runs one of FullControl's model notebooks and prints the G-code FullControl
itself makes of it, the reference of tests/it/fullcontrol.rs.

    python fc_gcode.py NOTEBOOK.ipynb '{"name": value, ...}'

The notebook's code cells run in order, as a reader runs them, except the
preview cells (`fc.transform(..., 'plot', ...)`), which draw and write nothing
the G-code needs. A design parameter named in the JSON is set in its cell
before the cell runs (its line `name = default` rewritten), so the values
derived from it below are derived from the new value. The G-code cell runs
with `printer_name='generic'`, the primer `no_primer`, no file saved, and
`fc.Extruder(on=True)` before the design (FullControl's extruder starts off;
only a primer turns it on). Nothing of FullControl or of its output is kept:
this file is p3dp's, the notebook and the package come at test time.
"""

import contextlib
import json
import re
import sys


def cells(path):
    with open(path, encoding="utf-8") as f:
        nb = json.load(f)
    for c in nb["cells"]:
        if c["cell_type"] == "code":
            yield "".join(c["source"])


def set_params(src, values):
    for name, v in values.items():
        pat = re.compile(r"^(\s*)" + re.escape(name) + r"\s*=(?!=).*$", re.M)
        src, n = pat.subn(lambda m: f"{m.group(1)}{name} = {v!r}", src, count=1)
        if not n:
            # one of several names of a line (`a, b, c = 1, 2, 3`): set it after the line
            multi = re.compile(r"^(\s*)([\w, ]*\b" + re.escape(name) + r"\b[\w, ]*=(?!=).*)$", re.M)
            src, n = multi.subn(lambda m: f"{m.group(1)}{m.group(2)}\n{m.group(1)}{name} = {v!r}", src, count=1)
        if n:
            values = {k: x for k, x in values.items() if k != name}
    return src, values


def gcode_cell(src):
    src = re.sub(r"printer_name\s*=\s*[^,\n)]+", "printer_name='generic'", src)
    src = re.sub(r"save_as\s*=\s*[^,\n)]+,?", "", src)
    src = re.sub(r"'primer'\s*:\s*'[^']*'", "'primer': 'no_primer'", src)
    if "'primer'" not in src:
        src = src.replace("initialization_data={", "initialization_data={'primer': 'no_primer', ", 1)
    return src.replace(
        "fc.transform(steps, 'gcode'", "fc.transform([fc.Extruder(on=True)] + steps, 'gcode'"
    )


def run(path, values):
    """Runs the notebook's cells; its G-code and the values no cell named."""
    scope = {}
    for src in cells(path):
        if re.search(r"fc\.transform\([^\n]*'plot'", src) and "GcodeControls" not in src:
            continue
        if "GcodeControls" in src:
            exec(compile(gcode_cell(src), path, "exec"), scope)
            return scope["gcode"], values
        src, values = set_params(src, values)
        exec(compile(src, path, "exec"), scope)
    return None, values


def main():
    path, values = sys.argv[1], json.loads(sys.argv[2]) if len(sys.argv) > 2 else {}
    # FullControl's tips and the notebooks' prints go to stderr: stdout is the G-code
    with contextlib.redirect_stdout(sys.stderr):
        out, values = run(path, values)
    if values:
        sys.exit(f"no design parameter named {', '.join(values)} in {path}")
    if out is None:
        sys.exit(f"no G-code cell in {path}")
    sys.stdout.write(out)


main()
