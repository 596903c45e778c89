"""Shared helpers of the lsmorph validation studies (run with /usr/bin/python3).

Every study script is called as

    /usr/bin/python3 validation/studyN_*.py BUILD_DIR REPORT_DIR

and writes its CSV files and PNG plots into REPORT_DIR, and its part of the
report into REPORT_DIR/sections/N.md plus REPORT_DIR/sections/N.json (title,
wall time).  validation/report.py assembles REPORT.md from the sections.
Nothing in the report is typed in by hand: every number comes from a file the
run wrote.
"""
import csv
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import time
import zlib

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BUNNY_DIR = os.path.join(ROOT, "examples", "data", "bunny")


METHOD_COLORS = {"ls": "tab:blue", "ls-opencl": "tab:cyan", "pls": "tab:green", "blend": "tab:orange",
                 "nearest": "tab:gray"}


class StepFailed(RuntimeError):
    pass


def log(msg):
    print("validate: " + msg, file=sys.stderr, flush=True)


def run(cmd, capture=True, cwd=ROOT):
    """Runs a command; raises StepFailed (with its stderr) on a non-zero exit."""
    t0 = time.time()
    proc = subprocess.run(cmd, cwd=cwd, stdout=subprocess.PIPE if capture else None,
                          stderr=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        raise StepFailed("command failed (exit %d): %s\n%s" % (
            proc.returncode, " ".join(cmd), (proc.stderr or "")[-4000:]))
    if proc.stderr and not capture:
        sys.stderr.write(proc.stderr)
    return proc.stdout if capture else "", time.time() - t0


class Study:
    """Paths and bookkeeping of one study."""

    def __init__(self, number, title, argv):
        if len(argv) != 3:
            sys.exit("usage: %s BUILD_DIR REPORT_DIR" % argv[0])
        self.number = number
        self.title = title
        self.build = os.path.abspath(argv[1])
        self.report = os.path.abspath(argv[2])
        self.work = os.path.join(self.report, "work", "study%d" % number)
        self.sections = os.path.join(self.report, "sections")
        self.t0 = time.time()
        self.lines = []
        shutil.rmtree(self.work, ignore_errors=True)
        os.makedirs(self.work, exist_ok=True)
        os.makedirs(self.sections, exist_ok=True)
        self.lsmorph = os.path.join(self.build, "lsmorph")
        for exe in [self.lsmorph]:
            if not os.access(exe, os.X_OK):
                raise StepFailed("missing %s: run make first" % exe)
        self.threads = os.cpu_count() or 1
        self.help = run([self.lsmorph, "help", "reconstruct"])[0]
        self.methods = self._methods()
        self.align_modes = self._choices("--align")
        self.has_interp = "--interp" in self.help
        self.backends = self._choices("--backend")

    def _choices(self, option):
        import re
        m = re.search(r"^ {1,4}" + re.escape(option) + r"\s+([a-z0-9-]+(?:\|[a-z0-9-]+)+)", self.help,
                      re.M)
        return m.group(1).split("|") if m else []

    def _methods(self):
        """Methods to validate: the CLI's (ls, blend, pls when offered), or the
        comma-separated list in VALIDATE_METHODS."""
        offered = self._choices("--method") or ["ls"]
        want = os.environ.get("VALIDATE_METHODS")
        if want:
            bad = [m for m in want.split(",") if m not in offered]
            if bad:
                raise StepFailed("VALIDATE_METHODS: %s not offered by this lsmorph" % ", ".join(bad))
            return want.split(",")
        return [m for m in ("ls", "pls", "blend") if m in offered]

    def opencl_works(self):
        """1 if `lsmorph devices` lists a device (cached)."""
        if not hasattr(self, "_opencl"):
            self._opencl = False
            self.opencl_device = ""
            if "opencl" in self.backends:
                try:
                    out = subprocess.run([self.lsmorph, "devices"], capture_output=True,
                                         text=True, timeout=60)
                    lines = [l.strip() for l in out.stdout.splitlines() if l.strip()]
                    self._opencl = out.returncode == 0 and len(lines) > 0
                    self.opencl_device = lines[-1] if lines else ""
                except (OSError, subprocess.SubprocessError):
                    self._opencl = False
        return self._opencl

    def method_args(self, method):
        return [] if method == "ls" else ["--method", method]

    def tool(self, name):
        path = os.path.join(self.build, "validation", name)
        if not os.access(path, os.X_OK):
            raise StepFailed("missing %s: run make validate (builds validation/*.c)" % path)
        return path

    def example(self, name):
        path = os.path.join(self.build, "examples", name)
        if not os.access(path, os.X_OK):
            raise StepFailed("missing %s: run make" % path)
        return path

    def out(self, name):
        return os.path.join(self.report, name)

    def md(self, text=""):
        self.lines.append(text)

    def finish(self, keep_work=False):
        secs = time.time() - self.t0
        with open(os.path.join(self.sections, "%d.md" % self.number), "w") as f:
            f.write("\n".join(self.lines).rstrip() + "\n")
        with open(os.path.join(self.sections, "%d.json" % self.number), "w") as f:
            json.dump({"number": self.number, "title": self.title, "seconds": secs,
                       "finished": time.strftime("%Y-%m-%d %H:%M:%S")}, f)
        if not keep_work:
            shutil.rmtree(self.work, ignore_errors=True)
        log("study %d (%s) done in %.1f s" % (self.number, self.title, secs))

    # ---- lsmorph -------------------------------------------------------------------

    def reconstruct(self, in_dir, out_dir, args):
        os.makedirs(os.path.dirname(os.path.abspath(out_dir)), exist_ok=True)
        cmd = [self.lsmorph, "reconstruct", in_dir, "-o", out_dir, "-q",
               "--threads", str(self.threads)] + list(args)
        if "--no-preview" in self.help:
            cmd.append("--no-preview")
        _, secs = run(cmd)
        with open(os.path.join(out_dir, "run.json")) as f:
            info = json.load(f)
        info["_wall"] = secs
        return info

    def score(self, truth_dir, out_dir, stride):
        out, _ = run([self.lsmorph, "score", truth_dir, out_dir, "--stride", str(stride)])
        return json.loads(out.strip().splitlines()[-1])

    def slicescore(self, triples):
        """Scores (id, result_png, truth_png) triples with lsm_score_slice."""
        listing = os.path.join(self.work, "slicescore-list.txt")
        with open(listing, "w") as f:
            for t in triples:
                f.write("%s %s %s\n" % t)
        out, _ = run([self.tool("slicescore"), listing])
        rows = list(csv.DictReader(out.splitlines()))
        for r in rows:
            for k in ("dice", "hd95", "hd_max", "mean_surface"):
                r[k] = float(r[k]) if r[k] != "" else float("nan")
            for k in ("area_result", "area_truth", "comparable", "components_result",
                      "components_truth", "stray_components", "stray_pixels"):
                r[k] = int(r[k])
        return rows


# ---- PNG ------------------------------------------------------------------------------

def read_mask(path):
    """Binary mask of a slice PNG (foreground: luminance >= 50 %)."""
    a = mpimg.imread(path)
    if a.ndim == 3:
        a = a[..., :3].mean(axis=2)
    if a.dtype != np.float32 and a.dtype != np.float64:
        a = a / float(np.iinfo(a.dtype).max)
    return a >= 0.5


def write_mask(path, mask):
    """Minimal 8-bit grayscale PNG writer (zlib), 255 inside."""
    m = np.asarray(mask, dtype=bool)
    h, w = m.shape
    raw = b"".join(b"\x00" + (m[y].astype(np.uint8) * 255).tobytes() for y in range(h))

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def list_pngs(folder):
    """PNG files of a folder in natural order (as lsmorph lists them)."""
    import re
    names = [n for n in os.listdir(folder) if n.lower().endswith(".png")]

    def key(n):
        return [(0, int(t), "") if t.isdigit() else (1, 0, t) for t in re.findall(r"\d+|\D+", n)]
    return [os.path.join(folder, n) for n in sorted(names, key=key)]


def sample_inputs(truth_files, stride, dest):
    """Copies every stride-th slice (the 1st, stride+1-th, ...) into dest.
    Returns the kept 0-based indices."""
    os.makedirs(dest, exist_ok=True)
    kept = list(range(0, len(truth_files), stride))
    for k in kept:
        shutil.copyfile(truth_files[k], os.path.join(dest, "%03d.png" % (k + 1)))
    return kept


def nearest_result(truth_files, kept, dest):
    """The nearest-slice method: output slice n is the kept slice nearest to n
    (ties go to the lower slice), for n up to the last kept slice.  Written in
    the layout of a reconstruction (dest/slices/00001.png ...)."""
    sd = os.path.join(dest, "slices")
    os.makedirs(sd, exist_ok=True)
    last = kept[-1]
    kept_arr = np.array(kept)
    for n in range(last + 1):
        d = np.abs(kept_arr - n)
        src = kept_arr[int(np.argmin(d))]  # argmin takes the first, i.e. the lower one
        shutil.copyfile(truth_files[src], os.path.join(sd, "%05d.png" % (n + 1)))


def result_slices(out_dir):
    return list_pngs(os.path.join(out_dir, "slices"))


# ---- tables and files -----------------------------------------------------------------

def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in rows:
            w.writerow([fmt_csv(v) for v in r])


def fmt_csv(v):
    if isinstance(v, float):
        if math.isnan(v):
            return ""
        return "%.6g" % v
    return v


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def fnum(v, digits=3, sci=False):
    if v is None:
        return "–"
    if isinstance(v, str):
        return v
    if isinstance(v, float) and (math.isnan(v) or math.isinf(v)):
        return "–" if math.isnan(v) else "inf"
    if sci:
        return "%.*e" % (digits - 1, v)
    return "%.*f" % (digits, v)


def md_table(header, rows, align=None):
    out = ["| " + " | ".join(header) + " |"]
    if align is None:
        align = ["l"] + ["r"] * (len(header) - 1)
    out.append("|" + "|".join(":--" if a == "l" else "--:" for a in align) + "|")
    for r in rows:
        out.append("| " + " | ".join(str(c) for c in r) + " |")
    return "\n".join(out)


def rel(study, path):
    """Path relative to the report folder (for links in REPORT.md)."""
    return os.path.relpath(path, study.report)


def save_fig(fig, path):
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def boundary(mask):
    m = np.asarray(mask, dtype=bool)
    p = np.pad(m, 1, constant_values=False)
    inner = p[1:-1, 1:-1] & p[:-2, 1:-1] & p[2:, 1:-1] & p[1:-1, :-2] & p[1:-1, 2:]
    return m & ~inner


def overlay(result, truth):
    """RGB panel: result in light gray, truth boundary in red."""
    img = np.ones(result.shape + (3,), dtype=float)
    img[result] = (0.62, 0.62, 0.62)
    img[boundary(truth)] = (0.85, 0.0, 0.0)
    return img


def crop_box(masks, pad=4):
    """Index box (rows, cols slices) around the union of masks, with a margin."""
    u = np.zeros_like(np.asarray(masks[0], dtype=bool))
    for m in masks:
        u |= np.asarray(m, dtype=bool)
    if not u.any():
        return (slice(None), slice(None))
    ys, xs = np.nonzero(u)
    h, w = u.shape
    return (slice(max(ys.min() - pad, 0), min(ys.max() + pad + 1, h)),
            slice(max(xs.min() - pad, 0), min(xs.max() + pad + 1, w)))


def cpu_model():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    import platform
    return platform.processor() or "unknown CPU"


def reconstruct_and_score(s, truth_dir, truth_files, stride, tag, variants):
    """Keeps every stride-th truth slice, runs each variant and scores it.

    variants: list of (name, args); args is the list of extra lsmorph options
    (method, alignment, ...), or None for the nearest-slice baseline.
    Returns {name: metrics dict} and {name: per-slice rows}."""
    in_dir = os.path.join(s.work, "in", "%s-%d" % (tag, stride))
    kept = sample_inputs(truth_files, stride, in_dir)
    last = kept[-1]
    results, per_slice = {}, {}
    for name, args in variants:
        safe = "".join(c if c.isalnum() else "-" for c in name)
        out = os.path.join(s.work, "out", "%s-%d-%s" % (tag, stride, safe))
        secs, options = float("nan"), {}
        if args is None:
            nearest_result(truth_files, kept, out)
        else:
            info = s.reconstruct(in_dir, out, ["--spacing", str(stride)] + list(args))
            secs, options = info["_wall"], info.get("options", {})
        js = s.score(truth_dir, out, stride)
        triples = [(str(n + 1), os.path.join(out, "slices", "%05d.png" % (n + 1)), truth_files[n])
                   for n in range(last + 1)]
        rows = s.slicescore(triples)
        held = [r for r in rows if (int(r["id"]) - 1) % stride != 0]
        kept_rows = [r for r in rows if (int(r["id"]) - 1) % stride == 0]
        area_r = sum(r["area_result"] for r in rows)
        area_t = sum(r["area_truth"] for r in rows)
        results[name] = {
            "dice": js["dice"], "dice_volume": js["dice_volume"], "hd95": js["hd95"],
            "hd95_pooled": js.get("hd95_pooled", float("nan")),
            "mean_surface": js["mean_surface"], "volume_error_heldout": js["volume_error"],
            "volume_error_whole": (area_r - area_t) / area_t if area_t else float("nan"),
            "one_sided_empty": js["one_sided_empty"], "held_out": js["held_out"],
            "seconds": secs, "options": options,
            # parts of the result touching no truth pixel, on slices where the truth is
            # not empty (an empty truth slice is counted as "one side empty" instead)
            "stray_components": sum(r["stray_components"] for r in held if r["area_truth"]),
            "stray_pixels": sum(r["stray_pixels"] for r in held if r["area_truth"]),
            "inputs_exact": all(r["area_result"] == r["area_truth"] and r["dice"] == 1.0
                                for r in kept_rows),
            # agreement of the per-slice scorer with `lsmorph score`
            "check_dice": abs(float(np.mean([r["dice"] for r in held])) - js["dice"]),
            "out": out,
        }
        per_slice[name] = rows
    return results, per_slice


def describe_options(options):
    """The solver settings of a run, from its run.json."""
    keys = ["method", "scheme", "time", "align", "interp", "cfl", "reinit_every"]
    return ", ".join("%s %s" % (k, options[k]) for k in keys if k in options)


def where_worse(ls, other, msd=False):
    """How the scores `ls` lose to `other` (lists of phrases; empty: nowhere):
    pooled Dice lower by more than 1e-4, mean HD95 (and with msd the mean
    surface distance) higher by more than 0.01 px when both average the same
    slices, or more slices with one side empty."""
    worse = []
    if ls["dice_volume"] < other["dice_volume"] - 1e-4:
        worse.append("Dice vol. %.4f vs %.4f" % (ls["dice_volume"], other["dice_volume"]))
    same = ls["one_sided_empty"] == other["one_sided_empty"]  # same slices averaged
    if same and ls["hd95"] > other["hd95"] + 0.01:
        worse.append("HD95 %.2f vs %.2f px" % (ls["hd95"], other["hd95"]))
    if msd and same and ls["mean_surface"] > other["mean_surface"] + 0.01:
        worse.append("MSD %.2f vs %.2f px" % (ls["mean_surface"], other["mean_surface"]))
    if ls["one_sided_empty"] > other["one_sided_empty"]:
        worse.append("%d vs %d slices with one side empty" % (
            ls["one_sided_empty"], other["one_sided_empty"]))
    return worse


def vanished_slices(rows, stride):
    """Held-out slices that are empty in the result although the truth there and
    both kept slices around them are non-empty."""
    by = {int(r["id"]): r for r in rows}
    bad = []
    for n, r in sorted(by.items()):
        if (n - 1) % stride == 0:
            continue
        lo, hi = (n - 1) // stride * stride + 1, ((n - 1) // stride + 1) * stride + 1
        if r["area_result"] == 0 and r["area_truth"] > 0 and lo in by and hi in by and \
                by[lo]["area_truth"] > 0 and by[hi]["area_truth"] > 0:
            bad.append(n)
    return bad
