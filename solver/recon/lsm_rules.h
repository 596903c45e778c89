/* lsm_rules: every reconstruction rule and tuned constant, in one table.
 *
 * A rule is a decision the reconstruction takes by default beyond the design
 * document's method (the per-pair morph, its alignment and the halfway rule
 * at empty slices).  Each can be switched off for experiments (reconstruct
 * --rules-off NAME,...; recorded in run.json as options.rules_off) and names
 * what it then falls back to.  A constant is a threshold a rule uses.
 * The measurements behind them are in validation/measurements/rules.md, their
 * effect on the frozen test split in validation/measurements/ablation.md.
 *
 * LSM_RULE_LIST: X(ID, "name", "what it does", "why", "what switching it off falls back to").
 * LSM_CONSTANT_LIST: X(field, default, "what it is and why").
 * Add new entries at the end of a group; names are a contract (scripts use them).
 */
#ifndef LSM_RULES_H
#define LSM_RULES_H

#include <stdint.h>
#include <stdio.h>

#include "solver/base/lsm_status.h"

#define LSM_RULE_LIST(X)                                                                          \
  /* alignment (lsm_frame) */                                                                     \
  X(ALIGN_AUTO, "align-auto",                                                                     \
    "--align auto aligns a pair on its hull centroids only when its shape moved (tests below)",   \
    "a morph in place shrinks a moved shape and grows it again beside; aligning every pair "      \
    "shifts shapes that only changed",                                                            \
    "no pair is aligned, as with --align none")                                                   \
  X(ALIGN_CENTROID_GAIN, "align-centroid-gain",                                                   \
    "auto: aligned only if the centroid shift makes the two overlap more than in place",          \
    "a centroid that moves while the overlap does not is a change of shape",                      \
    "not tested")                                                                                 \
  X(ALIGN_APART, "align-apart",                                                                   \
    "auto: a pair that barely touches in place (overlap < align_apart_overlap of the smaller) "   \
    "and whose best shift makes it somewhat alike (IoU >= align_apart_iou) is a move",            \
    "a shape that moved more than its width overlaps little, even when it turned a little",       \
    "this case is not a move")                                                                    \
  X(ALIGN_ALIKE, "align-alike",                                                                   \
    "auto: a pair whose best shift makes it alike (IoU >= align_alike_iou and align_alike_gain "  \
    "times the IoU in place) is a move",                                                          \
    "the shift explains most of the difference; a small section inside a large one does not",    \
    "this case is not a move")                                                                    \
  X(END_MOVES_ON, "end-moves-on",                                                                 \
    "cubic: where the object ends in a gap and the pair beyond is aligned, the end keeps moving " \
    "at that pair's centroid velocity",                                                           \
    "an oblique vessel ends where it was heading, not where it was last seen",                    \
    "the end stays in place")                                                                     \
  X(CENTROID_PCHIP, "centroid-pchip",                                                             \
    "cubic: an aligned pair's shift follows the monotone cubic through the neighbours' centroids", \
    "the centroid path is C1 across slices, as the z-profile is",                                 \
    "the straight segment between the two centroids")                                             \
  /* the working canvas (lsm_slice) */                                                            \
  X(BORDER_EXTENSION, "border-extension",                                                         \
    "a mask touching the image border goes on across it: the canvas margin repeats the border "   \
    "pixels",                                                                                     \
    "the border is not the object's boundary; with a background margin a band across the image " \
    "barely moved at its ends",                                                                   \
    "a background margin")                                                                        \
  /* moving parts (lsm_parts, lsm_gap) */                                                         \
  X(MOVING_PARTS, "moving-parts",                                                                 \
    "ls/pls, mask input, unaligned pairs: parts paired across the gap (each the other's "         \
    "nearest) that moved off their place travel on their own, as the blend of the two moved to "  \
    "the same place",                                                                             \
    "parts drifting apart (vessels, ears, legs) leave the centroid in place; in place they "      \
    "shrink away and grow again beside",                                                          \
    "every part is morphed in place")                                                             \
  X(PARTS_AREA, "parts-area",                                                                     \
    "a pair of parts has areas within a factor parts_area_ratio",                                 \
    "a part much larger or smaller is not the same part",                                         \
    "areas are not compared")                                                                     \
  X(FIELD_PARTS, "field-parts",                                                                   \
    "--motion field: two parts matched one to one in place and under the field take it when "     \
    "they do not overlap or each reaches half the larger half-thickness outside the other; "      \
    "other parts stay in place (the field zero on them); a pair with no such part is not "        \
    "registered",                                                                                 \
    "a field on the whole slice drags outlines toward parts that appear or vanish; a disc "       \
    "moved by less than half its radius blends in place",                                         \
    "the field of the whole slice pair everywhere")                                               \
  /* parts with no counterpart (lsm_unmatched) */                                                 \
  X(UNMATCHED, "unmatched",                                                                       \
    "ls/pls: a part overlapping nothing of the other slice, farther from it than its own depth "  \
    "R, ends near mid-gap (the other side's phi lowered to R inside it)",                         \
    "pulled toward distant shapes, a small part would vanish at once",                            \
    "the plain morph")                                                                            \
  X(UNMATCHED_NEAR, "unmatched-near",                                                             \
    "an unmatched part closer to the other side's shapes than its depth keeps the interpolation", \
    "it branches off its neighbour, from the right place",                                        \
    "it ends near mid-gap too")                                                                   \
  X(BRANCHES, "branches",                                                                         \
    "cubic: an unmatched part that was one piece, on the slice beyond, with a larger part that "  \
    "goes on keeps the interpolation",                                                            \
    "a branch splitting off a body recedes toward the body",                                      \
    "it ends near mid-gap like any unmatched part")                                               \
  /* the z-profile (lsm_zprofile) */                                                              \
  X(OMEGA, "omega",                                                                               \
    "cubic, ls/pls: the morph's departure from the straight line is weighted by "                 \
    "omega(s) = 16 s^2 (1 - s)^2",                                                                \
    "the morph's error has a logarithmic slope singularity at the slices; omega keeps the "       \
    "profile C1 there and is 1 at mid-gap",                                                       \
    "the departure is added unweighted")                                                          \
  X(CUBIC_RANGE, "cubic-range",                                                                   \
    "cubic: the profile is kept within the range of the gap's two slices",                        \
    "the spline plus the morph's departure must not overshoot its slices",                        \
    "not bounded")                                                                                \
  X(EDGE_SLOPE, "edge-slope",                                                                     \
    "cubic: where the data end on one side (no slice, or an empty one) the slope is PCHIP's "     \
    "non-centred three-point slope",                                                              \
    "a rounded solid's profile is curved at its last sections",                                   \
    "the gap's secant")                                                                           \
  X(EMPTY_ERODED, "empty-eroded",                                                                 \
    "cubic: in that three-point slope an empty slice beyond the other side counts as that "      \
    "side's section eroded by its largest depth",                                                 \
    "an object crossed by two sections still has a curved profile",                               \
    "the gap's secant there")                                                                     \
  X(END_SLOPE_SHRINK, "end-slope-shrink",                                                         \
    "cubic: next to an empty slice the slope only shrinks the section toward the end (0 where it " \
    "grows)",                                                                                     \
    "where the widest part lies between the last two slices the profile is flat there",           \
    "the three-point slope either way")                                                           \
  /* the two-sided morph and pinholes (lsm_two_sided, lsm_pinholes) */                            \
  X(TWO_SIDED, "two-sided",                                                                       \
    "ls/pls: the morph runs both ways, each used where its front retreats, joined by the union "  \
    "of the insides",                                                                             \
    "a front reaches parts of the target outside the source only as fast as the target's depth " \
    "allows: thin features arrive late",                                                          \
    "the forward morph alone")                                                                    \
  X(THIN_JOIN, "thin-join",                                                                       \
    "two-sided: where a cell is less than join_thin_px outside one slice and deeper inside the "  \
    "other, the outsides are joined instead",                                                     \
    "the union keeps thin notches, holes and sulci shut",                                         \
    "the union of the insides everywhere")                                                        \
  X(PINHOLE_BLEND, "pinhole-blend",                                                               \
    "two-sided: a pinhole of a slice (a closed outside everywhere thinner than join_thin_px) "     \
    "takes the blend of the two slices",                                                          \
    "a drifting hole fits neither join: it is shut or split; the blend moves it",                 \
    "the two-sided value")                                                                        \
  X(PINHOLE_FILL, "pinhole-fill",                                                                 \
    "ls/pls, between two slices without holes: an output hole of at most pinhole_fill_cells "      \
    "cells, each within pinhole_fill_thin_px of the inside and inside one slice, is filled",       \
    "the morph leaves such holes where two parts merge (a ridge of phi)",                         \
    "the holes are kept")                                                                         \
  X(ONE_PIECE, "one-piece",                                                                       \
    "ls/pls, between two non-empty slices: an output slice keeps at most as many parts as the "   \
    "slices' overlap groups allow (per group the larger of its two counts), the largest",         \
    "a part appearing between two slices grows as one piece; the morph's fronts leave specks "    \
    "where a new part's ridges cross the other slice's parts",                                    \
    "the specks are kept")                                                                        \
  /* where objects end (lsm_ends, lsm_gap_run) */                                                 \
  X(ENDS_AUTO, "ends-auto",                                                                       \
    "--ends auto: the tip where the empty slice is the stack's first or last, nothing past "      \
    "mid-gap where more slices lie beyond",                                                       \
    "a stack cut one slice beyond the object ends near that slice; a scan wider than the object " \
    "says nothing of where it ends",                                                              \
    "the tip everywhere, as with --ends tip")                                                     \
  X(END_LONE_FLAT, "end-lone-flat",                                                               \
    "cubic: a section with no slice beyond it (an object shorter than two gaps) ends as a flat "  \
    "end",                                                                                        \
    "nothing tells how it ends; closing it at mid-gap left half of each gap empty",               \
    "the paraboloid cap closing at mid-gap (the linear profile's)")                               \
  X(END_TREND, "end-trend",                                                                       \
    "cubic: the end's shape follows the per-cell z-slope of phi from the slice beyond "           \
    "(held where it widens)",                                                                     \
    "the end continues what the slices before it were doing",                                    \
    "the last section eroded uniformly (the area caps only)")                                     \
  X(END_TREND_REACH, "end-trend-reach",                                                           \
    "cubic: the trend is carried at most the height it was measured over past the last section", \
    "a slope over a short step (a pixel of alignment rounding) must not be multiplied by a long " \
    "gap",                                                                                        \
    "carried over the whole gap")                                                                 \
  X(END_PARTS, "end-parts",                                                                       \
    "cubic: each 8-connected component of the last section ends on its own",                     \
    "two kidneys, a paw beside a body end at their own pace",                                     \
    "the whole section is one part")                                                              \
  X(END_FLAT_SHARE, "end-flat-share",                                                             \
    "cubic: a part mostly outside the slice beyond (under end_share_flat nested) is a flat end, " \
    "from end_share_flat + end_share_ramp it narrows like the slices before, a share of each "    \
    "between",                                                                                    \
    "a tail or thin part meeting a wide body does not narrow like that body",                    \
    "every part with a slice beyond narrows like the slices before")                             \
  X(END_TIP_POWER, "end-tip-power",                                                               \
    "cubic: the tip past mid-gap, A_F (2 (1 - sigma))^p, is steeper (p from end_tip_flat to "     \
    "end_tip_narrow) where the section narrows toward the end by end_cone_from or more",          \
    "a narrowing end closes earlier in the second half of its gap",                               \
    "p = end_tip_flat everywhere")                                                                \
  X(END_LINE, "end-line",                                                                         \
    "cubic, no third section: the narrowing share is capped by the line through the areas of "    \
    "the last two sections",                                                                      \
    "cross-sections near the tip of a smooth surface shrink linearly in area",                    \
    "no line cap")                                                                                \
  X(END_PARABOLA, "end-parabola",                                                                 \
    "cubic: the narrowing share is capped by the parabola through the areas of the last three "   \
    "sections (or the last two and zero at the empty slice)",                                     \
    "a smooth solid's section area is close to quadratic in z near its end",                      \
    "no parabola cap")                                                                            \
  X(END_PARABOLA_VERTEX, "end-parabola-vertex",                                                   \
    "cubic: a parabola opening upward is held at its vertex past it",                             \
    "an area that shrank toward the last section does not grow again",                           \
    "the parabola as it is")                                                                      \
  X(END_FLOOR, "end-floor",                                                                       \
    "cubic: whatever closes an end keeps end_floor of a tip one power lower (the deepest cells)", \
    "a held-out slice left empty where the object still is costs the 95 % Hausdorff distance "    \
    "the image size",                                                                             \
    "no floor")                                                                                   \
  X(END_TIE_NEARER, "end-tie-nearer",                                                             \
    "cubic: where equally deep cells leaving together would keep less than half the cap, they "   \
    "stay when that comes nearer it",                                                             \
    "a section of a few pixels would drop to its centre cell at the first step",                  \
    "tied cells always leave together")                                                           \
  /* output and per-iteration mode */                                                             \
  X(ZERO_TIES, "zero-ties",                                                                       \
    "an output value of exactly 0 is written a millionth of a pixel below zero",                  \
    "a reader taking phi < 0 as inside then draws the same shape as slices/ (phi <= 0)",          \
    "zeros are written as zeros")                                                                 \
  X(EMPTY_DEPTH, "empty-depth",                                                                   \
    "per-iteration mode: an empty slice next to a full one is the constant R / ln 2 (blend: R), " \
    "R the full section's largest depth",                                                         \
    "the morph toward it then closes the object at mid-gap, the halfway rule",                    \
    "the empty slice's own far distance")

#define LSM_RULE_ID(id, name, what, why, off) LSM_RULE_##id,
typedef enum lsm_rule { LSM_RULE_LIST(LSM_RULE_ID) LSM_RULE_COUNT } lsm_rule;
#undef LSM_RULE_ID

#define LSM_CONSTANT_LIST(X)                                                                      \
  X(align_apart_overlap, 0.1, "align-apart: in-place overlap below this share of the smaller "    \
                              "section is barely touching")                                      \
  X(align_apart_iou, 0.25, "align-apart: IoU at the best shift from which the two are somewhat "  \
                           "alike")                                                               \
  X(align_alike_iou, 0.5, "align-alike: IoU at the best shift from which the two are alike")      \
  X(align_alike_gain, 1.5, "align-alike: and at least this many times the IoU in place")          \
  X(parts_area_ratio, 2.0, "parts-area: largest ratio of the two parts' areas")                   \
  X(parts_margin_px, 16.0, "moving-parts: margin of the window where a moving part's phi is "     \
                           "kept (its zero level is exact either way)")                           \
  X(unmatched_grow_px, 2.0, "unmatched: a component is its inside dilated by this, so its "       \
                            "front band goes with it")                                            \
  X(join_thin_px, 2.0, "thin-join, pinhole-blend: an outside thinner than this is thin")          \
  X(pinhole_fill_thin_px, 2.0, "pinhole-fill: a filled hole's cells lie within this of the "      \
                               "inside")                                                          \
  X(pinhole_fill_cells, 4.0, "pinhole-fill: largest hole filled, cells")                          \
  X(end_share_flat, 0.4, "end-flat-share: nested share below which a part is a flat end")         \
  X(end_share_ramp, 0.2, "end-flat-share: over this much more it turns into a narrowing end")     \
  X(end_tip_flat, 2.0, "end-tip-power: tip exponent of a flat end (a cone's area)")               \
  X(end_tip_narrow, 3.0, "end-tip-power: tip exponent of a narrowing end")                        \
  X(end_cone_from, 0.1, "end-tip-power: narrowing toward the end, (A_N - A_F) / A_F, at which "   \
                        "the tip is steepest")                                                    \
  X(end_floor, 0.1, "end-floor: share of a tip one power lower that an end keeps")             \
  X(motion_sigma_field_px, 6.0, "motion: Gaussian smoothing of the field after each update, px") \
  X(motion_sigma_update_px, 1.0, "motion: Gaussian smoothing of each update, px")                 \
  X(motion_clip_nodes, 5.0, "motion: distances clipped to this many node spacings of a level")

/* The rules switched on and the constants of a run (lsm_rules_default). */
typedef struct lsm_rules {
  uint64_t off; /* bit r set: rule r is switched off */
#define LSM_CONSTANT_FIELD(field, value, what) double field;
  LSM_CONSTANT_LIST(LSM_CONSTANT_FIELD)
#undef LSM_CONSTANT_FIELD
} lsm_rules;

/* Every rule on, every constant at its default. */
void lsm_rules_default(lsm_rules *rules);

/* The defaults, for callers that take NULL as "default rules". */
const lsm_rules *lsm_rules_defaults(void);

/* Whether a rule is on (rules NULL: the defaults, all on). */
static inline int lsm_rule_on(const lsm_rules *rules, lsm_rule rule) {
  return !rules || !(rules->off >> (unsigned)rule & 1u);
}

/* A rule's name ("align-auto"), or NULL past the list. */
const char *lsm_rule_name(lsm_rule rule);

/* Switches off the rules named in a comma-separated list ("" switches off
 * none).  Returns LSM_ERR_USAGE naming the first unknown name. */
lsm_status lsm_rules_switch_off(lsm_rules *rules, const char *names, lsm_err *err);

/* Prints the table: every rule with what, why and its fallback, every
 * constant with its default (`lsmorph help rules`). */
void lsm_rules_print(FILE *f);

#endif
