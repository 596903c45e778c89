"""Assembles validation/report/REPORT.md from the studies' sections and CSV files.

Usage: /usr/bin/python3 validation/report.py BUILD_DIR REPORT_DIR START_EPOCH_SECONDS

Everything in the headline summary is read from the CSV files the studies
wrote in this run.
"""
import json
import math
import os
import subprocess
import sys
import time
from collections import defaultdict

import vlib
from vlib import fnum, md_table

TITLES = {1: "Grid convergence against exact solutions", 2: "Morph accuracy at convergence",
          3: "Reconstruction of analytic solids", 4: "The document's synthetic sets",
          5: "Real data: the Stanford bunny",
          6: "Ablation of the reconstruction rules on the test split"}


def sh(cmd):
    try:
        return subprocess.run(cmd, cwd=vlib.ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                              text=True).stdout.strip()
    except OSError:
        return ""


def machine():
    mem = ""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal"):
                    mem = "%.1f GiB" % (int(line.split()[1]) / 1024 ** 2)
    except OSError:
        pass
    commit = sh(["git", "rev-parse", "--short", "HEAD"]) or "unknown (not a git checkout)"
    dirty = sh(["git", "status", "--porcelain", "--untracked-files=no"])
    if dirty and commit and not commit.startswith("unknown"):
        commit += " (working tree has uncommitted changes to tracked files)"
    return {"nproc": os.cpu_count(), "cpu": vlib.cpu_model(), "mem": mem,
            "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"), "commit": commit,
            "cc": sh(["cc", "--version"]).splitlines()[0] if sh(["cc", "--version"]) else "unknown",
            "kernel": sh(["uname", "-sr"])}


def load(report, name):
    path = os.path.join(report, name)
    return vlib.read_csv(path) if os.path.exists(path) else None


def headline(report):
    out = []
    rows = load(report, "convergence_circles_orders.csv")
    if rows:
        by = defaultdict(list)
        for r in rows:
            if int(r["N_coarse"]) >= 128 and r["order_l1"]:
                by[(r["scheme"], r["time"])].append(float(r["order_l1"]))
        fin = max(int(r["N_fine"]) for r in rows)
        band = ""
        circ = load(report, "convergence_circles.csv")
        if circ and "band_l1" in circ[0]:
            w = {int(r["N"]): float(r["band_l1"]) for r in circ
                 if r["case"] == "circle-shrink" and r["scheme"] == "weno5" and r["time"] == "rk3"
                 and r["t"] == "2"}
            ns = sorted(w)
            if len(ns) >= 2:
                orders = ", ".join("%.1f" % math.log2(w[a] / w[b]) for a, b in zip(ns, ns[1:])
                                   if w[a] > 0 and w[b] > 0)
                band = (" The error of phi itself within 2 dx of the front (no interpolation), "
                        "weno5/rk3, circle-shrink, t = 2: %s from N = %d to %d, orders %s "
                        "(third order from RK3 until the float32 floor)." % (
                            " -> ".join(fnum(w[n], 2, sci=True) for n in ns), ns[0], ns[-1],
                            orders))
        out.append("**1. Convergence (circles, exact solution):** observed L1 order of the front "
                   "position for N >= 128 (up to N = %d): %s. Upwind and Roe-Fix are first order "
                   "in space, so RK2/RK3 lower their error constant but not the order; weno5's "
                   "front order of about 2 is that of the measurement (crossings located by linear "
                   "interpolation between cells, second order: section 1).%s" % (fin, "; ".join(
                       "%s/%s %.2f–%.2f" % (k[0], k[1], min(v), max(v)) for k, v in sorted(by.items())),
                       band))
    rows = load(report, "convergence_squares_richardson.csv")
    if rows:
        p = {}
        for r in rows:
            if r["t"] == "2" and r["scheme"] == "upwind" and r["N"] == str(max(int(x["N"]) for x in rows)):
                p[(r["time"], r["quantity"])] = r["p_richardson"]
        out.append("**1. Convergence (square into square, Richardson):** upwind, t = 2, Richardson "
                   "order p of the diagonal (corner) position: %s; of the area: %s; axis position "
                   "against the exact value: see the table (Euler first order; RK2/RK3 reach the "
                   "float32 floor)." % (
                       ", ".join("%s %s" % (t, fnum(float(p[(t, "diag")]), 2) if p.get((t, "diag")) else "–")
                                 for t in ("euler", "rk2", "rk3")),
                       ", ".join("%s %s" % (t, fnum(float(p[(t, "area")]), 2) if p.get((t, "area")) else "–")
                                 for t in ("euler", "rk2", "rk3"))))
    rows = load(report, "morph_accuracy.csv")
    if rows:
        npass = sum(r["pass"] == "1" for r in rows)
        worst = max(rows, key=lambda r: float(r["band_max"]))
        worst_mean = max(rows, key=lambda r: float(r["band_mean"]))
        out.append("**2. Morph accuracy:** %s (%d of %d runs within max <= 0.5 px and mean <= "
                   "0.02 px on the band |phi_T| <= 2 px); worst max %.3g px (%s %s/%s), worst mean "
                   "%.3g px (%s). At the document's stopping rule CP <= 0.25 the band max reaches "
                   "%.2f px." % (
                       "PASS" if npass == len(rows) else "FAIL", npass, len(rows),
                       float(worst["band_max"]), worst["case"], worst["scheme"], worst["time"],
                       float(worst_mean["band_mean"]), worst_mean["case"],
                       max(float(r["doc_band_max"]) for r in rows)))
    rows = load(report, "solids.csv")
    if rows:
        methods = []
        cells = defaultdict(dict)
        for r in rows:
            if r["stride"] == "8":
                if r["method"] not in methods:
                    methods.append(r["method"])
                cells[r["solid"]][r["method"]] = "%.4f / %.2f" % (
                    float(r["dice_volume"]), float(r["hd95_mean"]))
        out.append("**3. Analytic solids, every 8th slice kept** (pooled Dice / mean HD95 px; "
                   "all strides in section 3):")
        out.append("")
        out.append(md_table(["solid"] + methods,
                            [[k] + [v.get(m, "–") for m in methods] for k, v in cells.items()]))
    rows = load(report, "pyramid_exact.csv")
    if rows:
        agg = defaultdict(lambda: [[], []])
        for r in rows:
            if r["is_input"] == "0":
                agg[r["variant"]][0].append(float(r["dice"]))
                if r["hd95"]:
                    agg[r["variant"]][1].append(float(r["hd95"]))
        out.append("")
        out.append("**4. Pyramid vs the exact rectangles** (mean Dice / mean HD95 px over the "
                   "intermediate slices): " + "; ".join(
                       "%s %.4f / %.2f" % (k, sum(d) / len(d), sum(h) / len(h)) for k, (d, h) in agg.items()) +
                   ". Slice counts and times of the per-iteration mode next to the document's: "
                   "table in section 4.")
    rows = load(report, "bunny.csv")
    if rows:
        variants = []
        for r in rows:
            if r["variant"] not in variants:
                variants.append(r["variant"])
        out.append("")
        out.append("**5. Bunny** (pooled Dice / pooled HD95 px / mean HD95 px / MSD px; /default = "
                   "the CLI's defaults):")
        out.append("")
        out.append(md_table(["variant"] + ["K = %s" % k for k in sorted({r["stride"] for r in rows}, key=int)], [
            [v] + ["%.4f / %.2f / %.2f / %.2f" % (float(r["dice_volume"]), float(r["hd95_pooled"]),
                                                float(r["hd95_mean"]), float(r["mean_surface"]))
                   for k in sorted({r["stride"] for r in rows}, key=int)
                   for r in rows if r["stride"] == k and r["variant"] == v]
            for v in variants]))
    rows = load(report, "ablation.csv")
    if rows:
        strides = [c.split("_")[1] for c in rows[0] if c.startswith("ddice_")]
        acting = [r["rule"] for r in rows
                  if any(abs(float(r["ddice_" + k])) >= 0.001 for k in strides)]
        out.append("")
        out.append("**6. Rules on the test split** (section 6): %d rules switched off one at a "
                   "time; %d move the mean held-out Dice by 0.001 or more at some stride (%s), "
                   "the others less." % (len(rows), len(acting),
                                         ", ".join("`%s`" % r for r in acting) or "none"))
    return out


def main():
    if len(sys.argv) not in (4, 5):
        sys.exit("usage: report.py BUILD_DIR REPORT_DIR START_EPOCH_SECONDS [SHOWN_BUILD_DIR]")
    build, report, start = sys.argv[1], sys.argv[2], float(sys.argv[3])
    shown_build = sys.argv[4] if len(sys.argv) == 5 else build
    partial = os.environ.get("VALIDATE_PARTIAL") or None
    sec_dir = os.path.join(report, "sections")
    done = {}
    for n in TITLES:
        j = os.path.join(sec_dir, "%d.json" % n)
        if os.path.exists(j):
            with open(j) as f:
                done[n] = json.load(f)
    m = machine()
    version = sh([os.path.join(build, "lsmorph"), "--version"])
    total = time.time() - start
    help_text = sh([os.path.join(build, "lsmorph"), "help", "reconstruct"])
    import re

    def choices(option):
        mm = re.search(r"^ {1,4}" + re.escape(option) + r"\s+([a-z0-9-]+(?:\|[a-z0-9-]+)+)", help_text,
                       re.M)
        return mm.group(1).split("|") if mm else []
    methods = choices("--method")
    backends = choices("--backend")
    load_start = ""
    lp = os.path.join(sec_dir, "loadavg_start.txt")
    if os.path.exists(lp):
        with open(lp) as f:
            load_start = " ".join(f.read().split()[:3])
    try:
        with open("/proc/loadavg") as f:
            load_end = " ".join(f.read().split()[:3])
    except OSError:
        load_end = "?"
    L = []
    L.append("# lsmorph validation report")
    L.append("")
    L.append("Generated by `make validate` (`sh validation/run.sh %s`; the binaries of that "
             "build folder are copied once at the start, so the whole run uses one build). "
             "Every number, table and plot below was computed by this run from files it "
             "wrote; the only values not computed here are the design document's timings in "
             "section 4, cited as the document's." % os.path.relpath(shown_build, vlib.ROOT))
    L.append("")
    L.append(md_table(["", ""], [
        ["date", m["date"]], ["git commit", m["commit"]], ["lsmorph", version or "?"],
        ["machine", "%s, %s logical CPUs (nproc), %s RAM, %s" % (m["cpu"], m["nproc"], m["mem"],
                                                               m["kernel"])],
        ["compiler", m["cc"]],
        ["load average (1/5/15 min)", "at start %s; at end %s (the machine may be shared: "
                                      "timings are indicative)" % (load_start or "?", load_end)],
        ["total run time", "%.1f s (%.1f min) for %s and this report; compilation "
                           "not included" % (total, total / 60, "the studies" if partial is None
                                             else "study " + partial + " only (a partial run)")]] +
        [["study %d time" % n, "%.1f s" % done[n]["seconds"] if n in done else "not run"]
         for n in TITLES]))
    L.append("")
    L.append("## What is measured, and how")
    L.append("")
    L.append("lsmorph fills the gaps between sparse parallel binary slices by level-set "
             "morphing, phi_t + (phi - phi_target)|grad phi| = 0 (solver/README.md). The studies:")
    L.append("")
    L.append("1. **Grid convergence** of the solver itself (`lsm_morph` on analytic signed "
             "distance functions): concentric circles, whose front radius is known exactly, "
             "for both spatial schemes (upwind, Roe-Fix) and all integrators (Euler, RK2, "
             "RK3) on grids 32..1024; a shrinking square (corners) against a Richardson "
             "extrapolation. Observed orders between consecutive grids.")
    L.append("2. **Morph accuracy**: run the morph to convergence and measure how close phi "
             "gets to phi_target near the target front (OpenVDB morph-test style; targets "
             "max <= 0.5 px, mean <= 0.02 px), for a disc pair and the document's shape pairs.")
    L.append("3. **Analytic solids** sampled every 4th/8th/16th slice, reconstructed by the "
             "CLI in default mode, every held-out slice scored against the exact solid "
             "(Dice, surface distances, volume), against the blend and nearest-slice baselines.")
    L.append("4. **The document's synthetic sets**: slice counts and time per slice of the "
             "document's per-iteration mode next to the document's table, and the Pyramid's "
             "cross-sections against the exact interpolated rectangles.")
    L.append("5. **Real data** (the Stanford bunny, 128^3): as study 3, with and without hull "
             "alignment.")
    L.append("6. **Ablation of the rules**: each reconstruction rule (`lsmorph help rules`) "
             "switched off alone on the frozen test split (`validation/split.py`), every 4th and "
             "8th slice kept: its effect on the mean held-out Dice and HD95.")
    L.append("")
    notes = []
    if "opencl" not in backends:
        notes.append("there is no OpenCL backend in this lsmorph: only the C backend is "
                     "validated")
    else:
        notes.append("this lsmorph offers `--backend %s`; the C backend (the reference, "
                     "the default) is validated throughout, and study 3 also runs the default "
                     "method on OpenCL (`ls-opencl`) when a device opens" % "|".join(backends))
    if "pls" not in methods:
        notes.append("there is no particle level set (PLS) method in this lsmorph yet")
    else:
        notes.append("PLS (`--method pls`) is validated in studies 3–5 with its default "
                     "settings; studies 1–2 exercise the level-set core (`lsm_morph`) only")
    L.append("Scope: " + "; ".join(notes) + ".")
    L.append("")
    L.append("## Headline numbers")
    L.append("")
    for para in headline(report):
        L.append(para)
        if para:
            L.append("")
    L.append("")
    for n in TITLES:
        path = os.path.join(sec_dir, "%d.md" % n)
        if n in done and os.path.exists(path):
            with open(path) as f:
                L.append(f.read().rstrip())
            L.append("")
            L.append("*(study %d: %.1f s, finished %s)*" % (n, done[n]["seconds"], done[n]["finished"]))
        else:
            L.append("## %d. %s" % (n, TITLES[n]))
            L.append("")
            L.append("Not run in this invocation.")
        L.append("")
    with open(os.path.join(report, "REPORT.md"), "w") as f:
        f.write("\n".join(L).rstrip() + "\n")
    vlib.log("wrote %s (total %.1f s)" % (os.path.join(report, "REPORT.md"), total))
    if any(math.isnan(x["seconds"]) for x in done.values()):
        sys.exit(1)


if __name__ == "__main__":
    main()
