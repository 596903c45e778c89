"""Study 2: morph accuracy at convergence (OpenVDB morph-test style).

Runs build/validation/morphacc (validation/morphacc.c) on a disc moving to an
offset disc and on consecutive slices of the document's synthetic sets
(gen_synthetic), and reports |phi - phi_target| on the band |phi_target| <= 2 px.
"""
import os
import sys
from collections import defaultdict

import vlib
from vlib import fnum, md_table, plt

MAX_TARGET = 0.5
MEAN_TARGET = 0.02


def main():
    s = vlib.Study(2, "Morph accuracy at convergence", sys.argv)
    synth = os.path.join(s.work, "synthetic")
    os.makedirs(synth, exist_ok=True)
    vlib.run([s.example("gen_synthetic"), "all", synth])
    vlib.log("study 2: morph to convergence, 12 pairs x 4 scheme/integrator combinations")
    vlib.run([s.tool("morphacc"), synth, s.report, "--threads", str(s.threads)])
    rows = vlib.read_csv(s.out("morph_accuracy.csv"))
    hist = vlib.read_csv(s.out("morph_history.csv"))

    s.md("## 2. Morph accuracy at convergence")
    s.md()
    s.md("Driver: `validation/morphacc.c`. In the style of OpenVDB's level-set morph test, "
         "the morph phi_t + (phi - phi_T)|grad phi| = 0 runs from the source until it has "
         "converged — the change per step of ||phi - phi_T||_2 (the document's CP) below "
         "1e-6 px x sqrt(cells), or t = 60 — and then |phi - phi_T| is measured on the band "
         "|phi_T| <= 2 px around the target front. Targets: **max <= %.1f px and mean <= %.2f "
         "px**. Pairs: a disc of radius 20 moving to a disc of radius 16 offset by (28, -6) "
         "px (analytic SDFs, 128 x 128), and every consecutive pair of the document's "
         "synthetic sets (gen_synthetic outlines; phi from `lsm_sdf_from_outline`, as the "
         "solver builds it; the sets are centred, so no alignment is involved). No "
         "reinitialisation (the solver's default). The last columns give the band error at "
         "the step where the document's stopping rule CP <= 0.25 (solver/README.md §12) first "
         "holds." % (MAX_TARGET, MEAN_TARGET))
    s.md()
    table = []
    n_pass = 0
    worst_max = (0.0, "")
    worst_mean = (0.0, "")
    for r in rows:
        mx, mn = float(r["band_max"]), float(r["band_mean"])
        ok = mx <= MAX_TARGET and mn <= MEAN_TARGET
        n_pass += ok
        tag = "%s %s/%s" % (r["case"], r["scheme"], r["time"])
        if mx > worst_max[0]:
            worst_max = (mx, tag)
        if mn > worst_mean[0]:
            worst_mean = (mn, tag)
        table.append([r["case"], r["scheme"], r["time"], r["iterations"], fnum(float(r["t_final"]), 1),
                      fnum(float(r["initial_max"]), 2), fnum(mx, 2, True), fnum(mn, 2, True),
                      "pass" if ok else "**FAIL**", r["doc_iterations"],
                      fnum(float(r["doc_band_max"]), 3), fnum(float(r["doc_band_mean"]), 3)])
    s.md(md_table(["pair", "scheme", "integrator", "steps", "t end", "initial max",
                   "band max", "band mean", "verdict", "steps to CP<=0.25", "max at CP<=0.25",
                   "mean at CP<=0.25"], table, ["l", "l", "l"] + ["r"] * 9))
    s.md()
    verdict = "all %d runs pass" % len(rows) if n_pass == len(rows) else \
        "**%d of %d runs fail**" % (len(rows) - n_pass, len(rows))
    s.md("**Result: %s.** Worst band max %.3g px (%s), %.0f%% of the 0.5 px budget; worst "
         "band mean %.3g px (%s), %.0f%% of the 0.02 px budget." % (
             verdict, worst_max[0], worst_max[1], 100 * worst_max[0] / MAX_TARGET,
             worst_mean[0], worst_mean[1], 100 * worst_mean[0] / MEAN_TARGET))
    s.md()
    # The document's stopping rule.
    doc = [r for r in rows if r["scheme"] == "upwind" and r["time"] == "euler"]
    doc_fail = [r for r in doc if float(r["doc_band_max"]) > MAX_TARGET or
                float(r["doc_band_mean"]) > MEAN_TARGET]
    s.md("At the document's stopping rule (CP <= 0.25, upwind/Euler) the morph is far from "
         "converged: %d of %d pairs miss the targets there, with band max up to %.2f px "
         "and band mean up to %.3f px. CP is a difference of Frobenius norms over the whole "
         "grid, so this threshold stops a pair when the residual decays by less than 0.25 "
         "per step, which on these grid sizes happens around t = %.1f–%.1f." % (
             len(doc_fail), len(doc), max(float(r["doc_band_max"]) for r in doc),
             max(float(r["doc_band_mean"]) for r in doc),
             min(float(r["doc_t"]) for r in doc), max(float(r["doc_t"]) for r in doc)))
    s.md()
    s.md("Where the largest residual errors sit (upwind/Euler; cell column, row, phi_T "
         "there): " + "; ".join(
             "%s (%s, %s, %s)" % (r["case"], r["max_i"], r["max_j"], r["max_phi_target"])
             for r in doc if float(r["band_max"]) > 1e-3) +
         ". The residual is concentrated in a few cells (compare band max with band "
         "mean). For the vase pairs and candlestick-3-4 these cells sit at corners of the "
         "target squares (vase) and on the ridge of phi_T halfway between two candles "
         "(candlestick-3-4), where phi_T is not differentiable.")
    s.md()

    series = defaultdict(list)
    for h in hist:
        series[(h["case"], h["scheme"], h["time"])].append(
            (float(h["t"]), float(h["band_max"]), float(h["band_mean"])))
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5), sharey=True)
    cases = sorted({r["case"] for r in rows}, key=lambda c: [r["case"] for r in rows].index(c))
    cmap = plt.get_cmap("tab20")
    for k, case in enumerate(cases):
        pts = series[(case, "upwind", "euler")]
        for ax, col in ((axes[0], 1), (axes[1], 2)):
            ax.semilogy([p[0] for p in pts if p[0] > 0], [max(p[col], 1e-8) for p in pts if p[0] > 0],
                        color=cmap(k % 20), label=case)
    for ax, target, name in ((axes[0], MAX_TARGET, "max"), (axes[1], MEAN_TARGET, "mean")):
        ax.axhline(target, color="k", ls="--", lw=1, label="target %s" % name)
        ax.set_xscale("log")
        ax.set_xlabel("morph time t")
        ax.set_title("band |phi_T| <= 2 px: %s |phi - phi_T| (upwind/Euler)" % name)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("px")
    axes[1].legend(fontsize=7, ncol=2)
    vlib.save_fig(fig, s.out("morph_accuracy.png"))
    s.md("![morph accuracy](morph_accuracy.png)")
    s.md()
    s.md("CSV: [morph_accuracy.csv](morph_accuracy.csv) (final and CP <= 0.25 values), "
         "[morph_history.csv](morph_history.csv) (band error along the run).")
    s.finish()


if __name__ == "__main__":
    try:
        main()
    except vlib.StepFailed as e:
        sys.exit("validate: study 2 failed: %s" % e)
