"""Study 3: reconstruction of analytic solids sampled sparsely.

build/validation/solids writes full-resolution binary slices of five solids;
every K-th slice is kept, reconstructed with `lsmorph reconstruct --spacing K`
(default mode: output slice n is truth slice n), and every held-out slice is
scored against the exact rasterised solid.
"""
import os
import sys

import vlib
from vlib import fnum, md_table, plt

SOLIDS = ["ball", "ellipsoid", "cone", "torus", "two-balls"]
STRIDES = [4, 8, 16]
MONTAGE_SOLID = "torus"
MONTAGE_STRIDE = 16
MONTAGE_SLICES = [25, 41, 45, 57, 105]  # 1-based slice numbers (z = n - 1), held out at K = 16

def main():
    s = vlib.Study(3, "Reconstruction of analytic solids", sys.argv)
    solids_dir = os.path.join(s.work, "truth")
    vlib.run([s.tool("solids"), solids_dir])
    info = {r["solid"]: r for r in vlib.read_csv(os.path.join(solids_dir, "solids.csv"))}
    METHODS = s.methods + ["nearest"]
    variants = [(m, s.method_args(m)) for m in s.methods] + [("nearest", None)]
    if s.opencl_works():
        # the default method on the OpenCL backend (PoCL here): same numbers expected
        METHODS.insert(1, "ls-opencl")
        variants.insert(1, ("ls-opencl", ["--backend", "opencl"]))
    table, csv_rows, slice_rows = [], [], []
    metrics = {}
    per_slice_all = {}
    max_check = 0.0
    all_inputs_exact = True
    for solid in SOLIDS:
        truth_dir = os.path.join(solids_dir, solid)
        truth_files = vlib.list_pngs(truth_dir)
        for k in STRIDES:
            vlib.log("study 3: %s, every %d-th slice" % (solid, k))
            res, per = vlib.reconstruct_and_score(s, truth_dir, truth_files, k, solid, variants)
            for method in METHODS:
                m = res[method]
                metrics[(solid, k, method)] = m
                per_slice_all[(solid, k, method)] = per[method]
                max_check = max(max_check, m["check_dice"])
                if method != "nearest":
                    all_inputs_exact &= m["inputs_exact"]
                table.append([solid, k, method, fnum(m["dice"], 4), fnum(m["dice_volume"], 4),
                              fnum(m["mean_surface"], 2), fnum(m["hd95"], 2),
                              fnum(m["hd95_pooled"], 2), fnum(100 * m["volume_error_whole"], 2),
                              m["one_sided_empty"], "%d (%d px)" % (m["stray_components"],
                                                                    m["stray_pixels"])])
                csv_rows.append([solid, k, method, m["held_out"], m["dice"], m["dice_volume"],
                                 m["mean_surface"], m["hd95"], m["hd95_pooled"],
                                 m["volume_error_heldout"], m["volume_error_whole"],
                                 m["one_sided_empty"], m["stray_components"], m["stray_pixels"],
                                 m["seconds"]])
                for r in per[method]:
                    n = int(r["id"])
                    slice_rows.append([solid, k, method, n, int((n - 1) % k == 0), r["dice"],
                                       r["hd95"], r["mean_surface"], r["area_result"],
                                       r["area_truth"]])
    vlib.write_csv(s.out("solids.csv"),
                   ["solid", "stride", "method", "held_out", "dice_mean", "dice_volume",
                    "mean_surface", "hd95_mean", "hd95_pooled", "volume_error_heldout",
                    "volume_error_whole", "one_sided_empty", "stray_components", "stray_pixels",
                    "seconds"], csv_rows)
    vlib.write_csv(s.out("solids_per_slice.csv"),
                   ["solid", "stride", "method", "slice", "kept", "dice", "hd95", "mean_surface",
                    "area_result", "area_truth"], slice_rows)

    s.md("## 3. Reconstruction of analytic solids sampled sparsely")
    s.md()
    s.md("Truth: `validation/solids.c` rasterises five solids on 128 x 128 pixels and 129 "
         "slices (z = 0..128, isotropic unit voxels; a voxel is inside when its centre is "
         "inside the closed solid): " + "; ".join(
             "**%s** (%s voxels, analytic volume %.0f, slices %s–%s)" % (
                 n, info[n]["voxels"], float(info[n]["analytic_volume"]), info[n]["first_slice"],
                 info[n]["last_slice"]) for n in SOLIDS) +
         ". Ball r = 40; ellipsoid 50 x 30 x 40 tilted 30° about y (sections drift "
         "sideways); cone with a flat base r = 44 at z = 20 and apex at z = 116; torus R = 36, "
         "r = 14 with its axis along y, perpendicular to the slice normal (sections: two "
         "blobs for |z - 64| < 22, one blob beyond); two balls r = 30 whose centres are "
         "59.4 apart along a 45° line in x-z (one disc, then two, then one).")
    s.md()
    s.md("Every K-th slice (1st, K+1-th, ..., 129th; K = 4, 8, 16) is kept and "
         "reconstructed with `lsmorph reconstruct IN -o OUT --spacing K -q` in default mode "
         "(pixel size 1, so output slice n is truth slice n), all other options at their "
         "defaults (run.json of the ls runs: %s). Methods: %s, and **nearest** (each "
         "held-out slice is a copy of the nearest kept slice, ties to the lower one; "
         "computed in Python). Backend: C%s." % (
             vlib.describe_options(metrics[(SOLIDS[0], STRIDES[0], "ls")]["options"]),
             ", ".join("**%s**%s" % (m, "" if m == "ls" else " (`--method %s`)" % m)
                       for m in s.methods),
             "; **ls-opencl** is the default method on `--backend opencl` (%s)" % s.opencl_device
             if s.opencl_works() else " (no OpenCL device could be opened: OpenCL not validated)"))
    if "pls" not in s.methods:
        s.md()
        s.md("PLS is not part of this run (%s)." % (
            "excluded by VALIDATE_METHODS" if "pls" in s._choices("--method")
            else "this lsmorph has no PLS method yet"))
    s.md()
    s.md("Scoring: `lsmorph score TRUTH OUT --stride K` (solver/app/lsmorph.c score(), per "
         "held-out slice `lsm_score_slice`): **Dice mean** over held-out slices (0 on a "
         "slice where exactly one side is empty), **Dice vol.** pooled over all held-out "
         "voxels, **MSD** mean symmetric surface distance and **HD95** 95th percentile of "
         "the symmetric boundary-pixel distances, both in pixels and averaged over the "
         "held-out slices where both sides are non-empty (slices with one side empty are "
         "counted in the \"one side empty\" column instead), **HD95 pooled** the 95th percentile over the "
         "boundary distances of all held-out slices together (a one-sided empty slice "
         "counts with a penalty distance of 128 px per boundary pixel). **Vol. err.** is the "
         "relative volume error of the whole reconstruction (all slices up to the last "
         "kept one, which is the last slice here). **Stray comp.**: 8-connected components "
         "of the held-out result slices that touch no truth pixel, on slices where the "
         "truth is not empty (count and pixels; from `slicescore`). Per-slice values come from "
         "`validation/slicescore.c` (the same `lsm_score_slice`); its mean Dice agrees "
         "with `lsmorph score` to %.1e. Kept slices are reproduced exactly by every lsmorph method: "
         "%s." % (max_check, "yes, on every run" if all_inputs_exact else "**NO** (see CSV)"))
    s.md()
    s.md(md_table(["solid", "K", "method", "Dice mean", "Dice vol.", "MSD px", "HD95 px",
                   "HD95 pooled", "vol. err. %", "one side empty", "stray comp."], table,
                  ["l", "r", "l"] + ["r"] * 8))
    s.md()

    # Where does ls lose?
    losses, wins = [], 0
    for solid in SOLIDS:
        for k in STRIDES:
            ls = metrics[(solid, k, "ls")]
            for other in [m for m in METHODS if m != "ls"]:
                worse = vlib.where_worse(ls, metrics[(solid, k, other)])
                if worse:
                    losses.append("%s K=%d vs %s: %s" % (solid, k, other, ", ".join(worse)))
                else:
                    wins += 1
    s.md("**Where ls loses** (ls worse than another method by more than 1e-4 in pooled Dice "
         "or 0.01 px in mean HD95, or with more slices where one side is empty; the mean "
         "HD95 leaves those slices out, so it is compared only between runs with the same "
         "number of them): " + ("; ".join(losses) if losses else "nowhere") +
         ". ls is at least as good on these measures in %d of %d comparisons." % (
             wins, (len(METHODS) - 1) * len(SOLIDS) * len(STRIDES)))
    s.md()

    stray = []
    for solid in SOLIDS:
        for k in STRIDES:
            counts = {m: metrics[(solid, k, m)]["stray_components"] for m in METHODS}
            if len(set(counts[m] for m in s.methods)) > 1:
                stray.append("%s K=%d: %s" % (solid, k, ", ".join(
                    "%s %d (%d px)" % (m, counts[m], metrics[(solid, k, m)]["stray_pixels"])
                    for m in s.methods)))
    s.md("Runs where the lsmorph methods differ in stray components: %s." % (
        "; ".join(stray) if stray else "none"))
    s.md()
    vanished = []
    for solid in SOLIDS:
        for k in STRIDES:
            for method in METHODS:
                bad = vlib.vanished_slices(per_slice_all[(solid, k, method)], k)
                if bad:
                    vanished.append("%s K=%d %s: %s" % (solid, k, method, ", ".join(map(str, bad))))
    s.md("Held-out slices that come out **empty although both kept slices around them are "
         "not**: %s." % ("; ".join(vanished) if vanished else "none"))
    s.md()

    # Error-vs-sampling curves.
    fig, axes = plt.subplots(2, len(SOLIDS), figsize=(16, 6.5), sharex=True)
    colors = vlib.METHOD_COLORS
    for j, solid in enumerate(SOLIDS):
        for method in METHODS:
            d = [1 - metrics[(solid, k, method)]["dice_volume"] for k in STRIDES]
            h = [metrics[(solid, k, method)]["hd95"] for k in STRIDES]
            axes[0][j].semilogy(STRIDES, d, "-o", color=colors[method], label=method, ms=4)
            axes[1][j].plot(STRIDES, h, "-o", color=colors[method], label=method, ms=4)
        axes[0][j].set_title(solid)
        axes[1][j].set_xlabel("kept every K-th slice")
        axes[1][j].set_xticks(STRIDES)
        for ax in (axes[0][j], axes[1][j]):
            ax.grid(True, which="both", alpha=0.3)
    axes[0][0].set_ylabel("1 - Dice (pooled)")
    axes[1][0].set_ylabel("HD95 (px, mean over slices)")
    axes[0][0].legend(fontsize=8)
    vlib.save_fig(fig, s.out("solids_vs_sampling.png"))
    s.md("![error vs sampling](solids_vs_sampling.png)")
    s.md()

    # Per-slice Dice at K = 16.
    fig, axes = plt.subplots(1, len(SOLIDS), figsize=(17, 3.6), sharey=True)
    for j, solid in enumerate(SOLIDS):
        for method in METHODS:
            rows = per_slice_all[(solid, 16, method)]
            held = [r for r in rows if (int(r["id"]) - 1) % 16 != 0]
            axes[j].plot([int(r["id"]) for r in held], [r["dice"] for r in held], ".",
                         color=colors[method], label=method, ms=4)
        axes[j].set_title("%s, K = 16" % solid)
        axes[j].set_xlabel("slice")
        axes[j].grid(True, alpha=0.3)
    axes[0].set_ylabel("Dice of held-out slice")
    axes[0].set_ylim(0.5, 1.01)
    axes[0].legend(fontsize=8)
    vlib.save_fig(fig, s.out("solids_per_slice_k16.png"))
    s.md("Dice of every held-out slice at K = 16 (y axis cut at 0.5; slices where the "
         "reconstruction or the truth is empty have Dice 0):")
    s.md()
    s.md("![per-slice Dice](solids_per_slice_k16.png)")
    s.md()

    # Montage.
    truth_files = vlib.list_pngs(os.path.join(solids_dir, MONTAGE_SOLID))
    cols = ["truth"] + METHODS
    box = vlib.crop_box([vlib.read_mask(truth_files[n - 1]) for n in MONTAGE_SLICES] +
                        [vlib.read_mask(os.path.join(metrics[(MONTAGE_SOLID, MONTAGE_STRIDE, c)]["out"],
                                                     "slices", "%05d.png" % n))
                         for n in MONTAGE_SLICES for c in cols[1:]])
    fig, axes = plt.subplots(len(MONTAGE_SLICES), len(cols), figsize=(3.2 * len(cols),
                                                                       2.0 * len(MONTAGE_SLICES)))
    for i, n in enumerate(MONTAGE_SLICES):
        if (n - 1) % MONTAGE_STRIDE == 0:
            raise vlib.StepFailed("montage slice %d is a kept slice" % n)
        truth = vlib.read_mask(truth_files[n - 1])
        for j, c in enumerate(cols):
            ax = axes[i][j]
            if c == "truth":
                img = vlib.overlay(truth, truth)
                title = "truth z=%d" % (n - 1)
            else:
                out = metrics[(MONTAGE_SOLID, MONTAGE_STRIDE, c)]["out"]
                res = vlib.read_mask(os.path.join(out, "slices", "%05d.png" % n))
                img = vlib.overlay(res, truth)
                r = next(r for r in per_slice_all[(MONTAGE_SOLID, MONTAGE_STRIDE, c)]
                         if int(r["id"]) == n)
                title = "%s Dice %.3f" % (c, r["dice"])
            ax.imshow(img[box], interpolation="nearest")
            ax.set_title(title, fontsize=8)
            ax.axis("off")
    fig.suptitle("%s, every %d-th slice kept: gray = mask, red = truth boundary" % (
        MONTAGE_SOLID, MONTAGE_STRIDE), fontsize=9)
    vlib.save_fig(fig, s.out("solids_montage_torus.png"))
    s.md("Torus, K = 16, held-out slices (gray: reconstructed mask; red: boundary of the "
         "exact section; z = 42 is where the section changes from two blobs to one):")
    s.md()
    s.md("![torus montage](solids_montage_torus.png)")
    s.md()
    s.md("CSV: [solids.csv](solids.csv) (table above, with the held-out-only volume error "
         "and run times), [solids_per_slice.csv](solids_per_slice.csv) (every slice, every "
         "run).")
    s.finish()

if __name__ == "__main__":
    try:
        main()
    except vlib.StepFailed as e:
        sys.exit("validate: study 3 failed: %s" % e)
