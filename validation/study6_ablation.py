"""Study 6: what each reconstruction rule does on the frozen test split.

For every rule of `lsmorph help rules` (solver/recon/lsm_rules.h), every stack
of the test split (validation/split.py: organ stand-ins, analytic solids and
moving structures drawn from seeds no rule was tuned on) is reconstructed with
that rule switched off (`--rules-off NAME`, default options otherwise),
keeping every 4th and every 8th slice, and the held-out slices are scored
with `lsmorph score` against the stack.  The table gives, per rule, the change
of the mean held-out Dice and of the mean HD95 (means over the stacks of each
stack's mean over its held-out slices) against the default, and how many
stacks' slices moved at all.  A run whose slices are those of the default is
not scored again (its scores are the default's).

Writes ablation.csv (the table) and ablation_per_stack.csv into the report,
the section for REPORT.md, and the table on stdout.
"""
import concurrent.futures
import hashlib
import json
import os
import shutil
import subprocess
import sys

import numpy as np

import split
import vlib
from vlib import md_table

STRIDES = [4, 8]
NOTHING = 0.001  # issue 53: a rule moving mean Dice by less than this on the test split goes
# Rules that cannot change the output slices of a default run: not run, said so.
NOT_MEASURED = {
    "zero-ties": "moves values of exactly 0 a millionth of a pixel below zero: the slices "
                 "(phi <= 0) are the same by construction",
    "empty-depth": "acts in per-iteration mode only",
}


def rule_names(lsmorph):
    """The rules `lsmorph help rules` lists, in table order."""
    out, _ = vlib.run([lsmorph, "help", "rules"])
    names = []
    for line in out.splitlines():
        if line.startswith(("constants", "removed")):
            break
        if line and line[0].islower() and " " not in line and line.replace("-", "").isalpha():
            names.append(line)
    if not names:
        raise vlib.StepFailed("lsmorph help rules lists no rules")
    return names


def slices_digest(out_dir):
    h = hashlib.sha1()
    for path in vlib.result_slices(out_dir):
        with open(path, "rb") as f:
            h.update(f.read())
    return h.hexdigest()


class Job:
    def __init__(self, study, stack, stride, rule):
        self.study, self.stack, self.stride, self.rule = study, stack, stride, rule
        self.base = os.path.join(study.work, stack, "k%d" % stride)
        self.out = os.path.join(self.base, "out-" + (rule or "default"))

    def reconstruct(self):
        cmd = [self.study.lsmorph, "reconstruct", os.path.join(self.base, "kept"), "-o", self.out,
               "--spacing", str(self.stride), "-q", "--no-preview", "--threads", "1",
               "--values", "mask", "--format", "raw"]  # (the scores read slices/ only)
        if self.rule:
            cmd += ["--rules-off", self.rule]
        vlib.run(cmd)
        return slices_digest(self.out)

    def score(self):
        out, _ = vlib.run([self.study.lsmorph, "score", os.path.join(self.study.work, self.stack,
                                                                      "truth"),
                           self.out, "--stride", str(self.stride)])
        return json.loads(out.strip().splitlines()[-1])


def write_stack(study, name, volume):
    """The truth slices under work/NAME/truth, every k-th of them under
    work/NAME/kK/kept."""
    truth = os.path.join(study.work, name, "truth")
    os.makedirs(truth, exist_ok=True)
    for k in STRIDES:
        os.makedirs(os.path.join(study.work, name, "k%d" % k, "kept"), exist_ok=True)
    for i, sl in enumerate(volume):
        path = os.path.join(truth, "%04d.png" % (i + 1))
        vlib.write_mask(path, sl)
        for k in STRIDES:
            if i % k == 0:
                shutil.copyfile(path, os.path.join(study.work, name, "k%d" % k, "kept",
                                                   "%04d.png" % (i + 1)))


def main():
    s = vlib.Study(6, "Ablation of the reconstruction rules on the test split", sys.argv)
    # one thread per run, as many runs at once as there are cores
    os.environ["OMP_NUM_THREADS"] = "1"
    rules = [r for r in rule_names(s.lsmorph) if r not in NOT_MEASURED]
    skipped = [r for r in rule_names(s.lsmorph) if r in NOT_MEASURED]
    stacks = []
    for name, kind, volume in split.test_stacks():
        write_stack(s, name, volume)
        stacks.append((name, kind, len(volume)))
    vlib.log("study 6: %d test stacks, %d rules, strides %s" % (
        len(stacks), len(rules), ", ".join(map(str, STRIDES))))
    workers = max(1, min(s.threads, 8))
    default = {}  # (stack, k) -> (digest, score)

    def run_default(job):
        digest = job.reconstruct()
        return job, digest, job.score()

    with concurrent.futures.ThreadPoolExecutor(workers) as pool:
        for job, digest, score in pool.map(run_default, [Job(s, n, k, None) for n, _, _ in stacks
                                                          for k in STRIDES]):
            default[(job.stack, job.stride)] = (digest, score)
            shutil.rmtree(job.out, ignore_errors=True)

    def run_rule(job):
        digest = job.reconstruct()
        same = digest == default[(job.stack, job.stride)][0]
        score = default[(job.stack, job.stride)][1] if same else job.score()
        shutil.rmtree(job.out, ignore_errors=True)
        return job, not same, score

    results = {}  # (rule, stack, k) -> (moved, score)
    jobs = [Job(s, n, k, r) for r in rules for n, _, _ in stacks for k in STRIDES]
    with concurrent.futures.ThreadPoolExecutor(workers) as pool:
        for job, moved, score in pool.map(run_rule, jobs):
            results[(job.rule, job.stack, job.stride)] = (moved, score)
    names = [n for n, _, _ in stacks]

    def mean(key, rule, k):
        vals = [(results[(rule, n, k)][1] if rule else default[(n, k)][1])[key] for n in names]
        return float(np.nanmean(np.array(vals, float)))

    base = {k: (mean("dice", None, k), mean("hd95", None, k)) for k in STRIDES}
    rows, csv_rows, per_stack, nothing = [], [], [], []
    rows.append(["**default** (absolute)"] + [x for k in STRIDES for x in (
        "%.4f" % base[k][0], "%.3f" % base[k][1])] + ["", ""])
    for r in rules:
        deltas = {k: (mean("dice", r, k) - base[k][0], mean("hd95", r, k) - base[k][1])
                  for k in STRIDES}
        moved = [n for n in names if any(results[(r, n, k)][0] for k in STRIDES)]
        worst = min(results[(r, n, k)][1]["dice"] - default[(n, k)][1]["dice"]
                    for n in names for k in STRIDES)
        if all(abs(deltas[k][0]) < NOTHING for k in STRIDES):
            nothing.append(r)
        rows.append([r] + [x for k in STRIDES for x in ("%+.4f" % deltas[k][0],
                                                         "%+.3f" % deltas[k][1])] +
                    ["%d" % len(moved), "%+.4f" % worst])
        csv_rows.append([r] + [x for k in STRIDES for x in deltas[k]] + [len(moved), worst])
        for n in names:
            for k in STRIDES:
                moved_k, sc = results[(r, n, k)]
                d = default[(n, k)][1]
                per_stack.append([r, n, k, int(moved_k), sc["dice"] - d["dice"],
                                  sc["hd95"] - d["hd95"], sc["dice"], sc["hd95"],
                                  sc["one_sided_empty"]])
    header = ["rule off"] + [x for k in STRIDES for x in ("dDice every %d" % k,
                                                         "dHD95 every %d (px)" % k)] + \
             ["stacks moved (of %d)" % len(names), "worst stack dDice"]
    vlib.write_csv(s.out("ablation.csv"), ["rule"] + [x for k in STRIDES for x in (
        "ddice_%d" % k, "dhd95_%d" % k)] + ["stacks_moved", "worst_stack_ddice"], csv_rows)
    vlib.write_csv(s.out("ablation_per_stack.csv"), ["rule", "stack", "stride", "moved", "ddice",
                                                     "dhd95", "dice", "hd95", "one_sided_empty"],
                   per_stack)
    table = md_table(header, rows, ["l"] + ["r"] * (len(header) - 1))
    print("## Ablation of the reconstruction rules (test split, %d stacks)\n" % len(names))
    print(table)
    print("\nNo effect on mean Dice (|dDice| < %g at every stride): %s" % (
        NOTHING, ", ".join(nothing) or "none"))
    print("Not run (cannot change the slices of a default run): %s" % (", ".join(skipped) or "none"),
          flush=True)

    groups = {"organ": "organ stand-ins", "solid": "analytic solids", "motion": "moving structures"}
    kinds = {}
    for n, kind, depth in stacks:
        kinds.setdefault(groups.get(n.split("-")[0], kind), []).append(n)
    s.md("## 6. Ablation of the reconstruction rules on the test split")
    s.md()
    s.md("Each rule of `lsmorph help rules` switched off alone (`--rules-off NAME`, default "
         "options otherwise) on the %d stacks of the frozen test split (`validation/split.py`: "
         "%s, drawn from seeds no rule was tuned on), every %s slice kept, the held-out slices "
         "scored with `lsmorph score`. dDice and dHD95: the change of the mean held-out Dice "
         "and of the mean HD95 (px; slices non-empty on both sides) against the default, each "
         "the mean over the stacks of a stack's mean over its held-out slices; a negative dDice "
         "means the rule earns Dice. Stacks moved: stacks whose output slices differ from the "
         "default's at either stride. Worst stack dDice: the largest loss of one stack at one "
         "stride." % (len(names), ", ".join("%d %s" % (len(v), k) for k, v in kinds.items()),
                      " and every ".join("%dth" % k for k in STRIDES)))
    s.md()
    s.md(table)
    s.md()
    s.md("Rules that move the mean Dice by less than %g at every stride on this split: %s." % (
        NOTHING, ", ".join("`%s`" % r for r in nothing) if nothing else "none"))
    s.md()
    if skipped:
        s.md("Not run (they cannot change the slices of a default run): %s." % "; ".join(
            "`%s` %s" % (r, NOT_MEASURED[r]) for r in skipped))
        s.md()
    s.md("CSV: [ablation.csv](ablation.csv), [ablation_per_stack.csv](ablation_per_stack.csv).")
    s.finish()


if __name__ == "__main__":
    try:
        main()
    except vlib.StepFailed as e:
        sys.exit("validate: study 6 failed: %s" % e)
