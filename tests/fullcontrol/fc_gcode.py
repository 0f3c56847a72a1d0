"""Runs one of FullControl's model notebooks and prints the G-code FullControl
itself makes of it, the reference of tests/it/fullcontrol.rs.

    python fc_gcode.py NOTEBOOK.ipynb '{"name": value, ...}'

The notebook's code cells run in order, as a reader runs them, except the
preview cells (`fc.transform(..., 'plot', ...)`), which draw and write nothing
the G-code needs. A design parameter named in the JSON is set in its cell
before the cell runs (its line `name = default` rewritten), so the values
derived from it below are derived from the new value. The G-code cell runs
with the generic printer, the primer `no_primer`, no file saved, and
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


# the notebooks' preview switches: G-code mode is the reference
SWITCHES = {"output": "gcode", "target": "gcode"}


def capture(fc, made):
    """Stands in for `fc.transform(steps, 'gcode', controls)`: the generic
    printer, no primer, no file saved, the extruder on before the design."""

    def transform(steps, kind, controls):
        controls.printer_name = "generic"
        controls.save_as = None
        controls.initialization_data["primer"] = "no_primer"
        out = fc.transform([fc.Extruder(on=True)] + steps, kind, controls)
        made.append(out)
        return out

    return transform


def run(path, values):
    """Runs the notebook's cells; its G-code and the values no cell named."""
    scope, made = {}, []
    for src in cells(path):
        if "'gcode'" not in src and re.search(r"fc\.transform\([^\n]*'plot'", src):
            continue
        src = src.replace("fc.transform(steps, 'gcode'", "__fc_gcode(steps, 'gcode'")
        for name, v in SWITCHES.items():
            src = re.sub(r"^" + name + r"\s*=.*$", f"{name} = {v!r}", src, flags=re.M)
        src, values = set_params(src, values)
        if "__fc_gcode" in src and "__fc_gcode" not in scope:
            scope["__fc_gcode"] = capture(scope["fc"], made)
        exec(compile(src, path, "exec"), scope)
        if made:
            return made[0], values
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
