#!/bin/sh
# lsmorph as a 3D Slicer command-line module: `lsmorph --xml` (what Slicer asks an executable in
# its module paths for) and `lsmorph fill --xml` print the same Slicer Execution Model description;
# it parses and keeps the rules Slicer's parser enforces (flags of letters, digits and '_', no flag
# on an indexed parameter, label-map images in and out); the command lines Slicer builds from it
# (flags in order, booleans only when true, empty strings left out, then the indexed parameters)
# run, with the defaults and with every option changed, and give what `lsmorph fill` gives.
#   sh tests/test_slicer.sh BUILD_DIR
# Prints "slicer: N passed, N failed".
set -u
BUILD=${1:-build}
LSM="$BUILD/lsmorph"
PY=/usr/bin/python3
SUITE=slicer
. "$(dirname "$0")/harness.sh"
python_suite "nibabel, numpy" "python3-nibabel, python3-numpy"

"$LSM" --xml >"$TMP/a.xml" 2>"$TMP/e"
check "lsmorph --xml: exit 0" [ $? -eq 0 ]
"$LSM" fill --xml >"$TMP/b.xml" 2>"$TMP/e"
check "lsmorph fill --xml: exit 0" [ $? -eq 0 ]
check "the two descriptions are one" cmp -s "$TMP/a.xml" "$TMP/b.xml"
"$PY" "$HERE/fill_check.py" make "$TMP" >"$TMP/make.log" 2>&1 || { bad "making the volumes"; finish; }

run_checks "$TMP/log" "$PY" - "$TMP" "$LSM" <<'PYEOF'
import os, re, subprocess, sys
import xml.etree.ElementTree as ET
import numpy as np, nibabel as nib
d, lsm = sys.argv[1], sys.argv[2]
def report(good, what): print(("ok - " if good else "FAIL - ") + what)
root = ET.parse(os.path.join(d, "a.xml")).getroot()
report(root.tag == "executable" and root.findtext("title") == "Fill between slices (level set)",
       "the description parses: <executable>, \"%s\"" % root.findtext("title"))
for tag in ("category", "title", "description", "version", "documentation-url", "license", "contributor"):
    report(root.find(tag) is not None, "<%s> is there" % tag)
ident = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
params = [p for group in root.findall("parameters") for p in group
          if p.tag not in ("label", "description")]
images = [p for p in params if p.tag == "image"]
report([(p.get("type"), p.findtext("channel")) for p in images] == [("label", "input"), ("label", "output")],
       "one label map in, one out (<image type=\"label\">)")
for p in params:
    name, flag, index = p.findtext("name"), p.findtext("longflag"), p.findtext("index")
    good = bool(name and ident.match(name)) and (flag is None or ident.match(flag.lstrip("-")))
    good = good and not (flag and index) and (flag or index)
    if p.tag.endswith("enumeration"):
        good = good and p.findtext("default") in [e.text for e in p.findall("element")]
    report(good, "parameter %s: a valid name, a flag or an index (not both)%s"
           % (name, ", its default among its elements" if p.tag.endswith("enumeration") else ""))

def command_line(values, inp, out):
    """As Slicer's command-line module logic builds it."""
    cmd, indexed = [lsm], {}
    for p in params:
        value = values.get(p.findtext("name"), p.findtext("default") or "")
        if p.tag == "image":
            value = inp if p.findtext("channel") == "input" else out
        if p.findtext("index") is not None:
            indexed[int(p.findtext("index"))] = value
            continue
        flag = "--" + p.findtext("longflag").lstrip("-")
        if p.tag == "boolean":
            if value == "true":
                cmd.append(flag)
        elif p.tag in ("string", "file", "directory") and value == "":
            continue
        else:
            cmd += [flag, value]
    return cmd + [indexed[k] for k in sorted(indexed)]

def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    return r.returncode, r.stderr

src = os.path.join(d, "drawn.nrrd")  # Slicer hands CLI modules NRRD files
cases = [({}, []),
         ({"method": "blend", "interp": "linear", "ends": "tip", "align": "none", "threads": "1",
           "backend": "c", "slices": "0:40:4", "labels": "2,3", "axis": "k"},
          ["--method", "blend", "--interp", "linear", "--ends", "tip", "--align", "none",
           "--threads", "1", "--slices", "0:40:4", "--labels", "2,3", "--axis", "k"]),
         ({"scheme": "roe-fix", "time": "rk2", "cfl": "0.5"},
          ["--scheme", "roe-fix", "--time", "rk2", "--cfl", "0.5"])]
for n, (values, cli) in enumerate(cases):
    out = os.path.join(d, "slicer%d.nrrd" % n)
    cmd = command_line(values, src, out)
    rc, err = run(cmd)
    report(rc == 0, "Slicer's command line %s: exit 0 (%s)" % (" ".join(cmd[1:-2]), err.strip()[-200:]))
    ref = os.path.join(d, "ref%d.nrrd" % n)
    rc, err = run([lsm, "fill", src, "-o", ref, "-q"] + cli)
    same = rc == 0 and os.path.exists(out) and open(out, "rb").read() == open(ref, "rb").read()
    report(same, "it writes what lsmorph fill %s writes" % " ".join(cli))
PYEOF
finish
