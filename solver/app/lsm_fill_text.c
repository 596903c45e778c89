/* lsm_fill_text: fill's help and its 3D Slicer module description (the
 * Slicer Execution Model: <executable>, the label maps as <image type="label">,
 * the options as parameters).  Slicer's long flags may hold letters, digits
 * and underscores only: fill takes "_" for "-" in option names. */
#include <stdio.h>

#include "solver/app/lsm_cli.h"
#include "solver/app/lsm_fill_cmd.h"

static const char fill_help[] =
    "Usage: lsmorph fill LABELS -o OUT [options]\n"
    "       lsmorph fill LABELS OUT [options]\n"
    "       lsmorph fill --xml\n"
    "\n"
    "Fills the slices between the drawn slices of a label volume, every label at\n"
    "once: each label is morphed from drawn slice to drawn slice as 'reconstruct'\n"
    "morphs PNG slices, and each voxel of the slices between gets the label it lies\n"
    "deepest inside, or none.  LABELS and OUT are NIfTI-1/2 (.nii, .nii.gz) or NRRD\n"
    "(.nrrd, .seg.nrrd, .nhdr + data file) label volumes, read and written with\n"
    "nifticlib and teem.  OUT keeps LABELS' grid, affine or space directions and\n"
    "origin, header fields and key/value pairs (a .seg.nrrd its segments' names and\n"
    "colours) and voxel type (labels stored as floats become the smallest integer\n"
    "type that holds them); the drawn slices and the labels not filled come back\n"
    "exactly.  OUT is written beside its name and renamed into place when complete.\n"
    "\n"
    "Slices:\n"
    "  --axis i|j|k|auto      the axis the drawn slices lie across (default auto: the\n"
    "                         axis of the largest voxel spacing, the last on ties)\n"
    "  --slices LIST          the drawn slices, from 0: N, A:B (A to B), A:B:S (every\n"
    "                         S-th from A), A-B, comma separated; a listed slice\n"
    "                         without a label says nothing is there.  Default: every\n"
    "                         slice holding a label, plus one typical step (the\n"
    "                         median step between them) beyond the first and the\n"
    "                         last, taken as drawn empty where the volume has it so\n"
    "                         that objects end there (a note lists them).  The slices\n"
    "                         between the first and the last drawn slice that are not\n"
    "                         drawn are filled; their voxels of the labels filled are\n"
    "                         replaced\n"
    "  --labels LIST          the labels to fill (N or A:B, comma separated; default\n"
    "                         every non-zero value); the others are kept as they are,\n"
    "                         and only slices holding a label to fill count as drawn\n"
    "\n"
    "Method (as for 'lsmorph help reconstruct'):\n"
    "  --method ls|pls|blend, --interp cubic|linear, --align auto|hull|none,\n"
    "  --motion auto|field|none, --scheme, --time, --cfl, --reinit-every,\n"
    "  --reinit-iters, --max-iter, --particles-per-cell, --pls-reseed,\n"
    "  --pls-radius-adjust, --seed, --rules-off\n"
    "  --ends halfway|tip|auto  default halfway: the drawn slices were placed without\n"
    "                         regard to where each structure ends, so an end may lie\n"
    "                         anywhere in its gap, and mid-gap is the median\n"
    "\n"
    "Running:\n"
    "  --threads N            0 .. 4096 (default 0: all cores): labels side by side\n"
    "                         when there are as many as threads, else each label's\n"
    "                         gaps side by side\n"
    "  --backend c|opencl|auto, --device N   as for reconstruct\n"
    "  --max-voxels N         refuse larger volumes (default 1073741824 = 2^30)\n"
    "  --max-memory BYTES     refuse volumes estimated to need more memory\n"
    "                         (default: what is available at the start)\n"
    "  -q, --quiet            no notes or progress on stderr (errors still)\n"
    "  --xml                  print the 3D Slicer module description (Slicer runs\n"
    "                         'lsmorph --xml' and then 'lsmorph [flags] fill IN OUT')\n"
    "Option names may use '_' for '-' (--max_iter), as Slicer's flags must.\n"
    "\n"
    "Errors (exit status 1), all before any work: LABELS is not a label map (values\n"
    "that are not whole numbers; a 4D .seg.nrrd with overlapping layers), fewer than\n"
    "two drawn slices across the axis, OUT in a missing folder, a link to nothing or\n"
    "a mount point, memory or disk that do not fit (with the numbers).  Every slice\n"
    "drawn is a note: nothing to fill, OUT is LABELS copied.  Exit status 2: usage\n"
    "error.\n"
    "Score a result against a full segmentation with 'lsmorph score TRUTH OUT'.\n";

void lsm_fill_help(FILE *f) { fputs(fill_help, f); }

/* An enumeration parameter with its elements, the first the default. */
#define ENUM(name, label, desc, ...) \
  "    <string-enumeration>\n      <name>" name "</name>\n      <longflag>" name "</longflag>\n" \
  "      <label>" label "</label>\n      <description>" desc "</description>\n" __VA_ARGS__ \
  "    </string-enumeration>\n"
#define EL(x) "      <element>" x "</element>\n"
#define DEF(x) "      <default>" x "</default>\n"

static const char fill_xml_head[] =
    "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
    "<executable>\n"
    "  <category>Segmentation</category>\n"
    "  <title>Fill between slices (level set)</title>\n"
    "  <description><![CDATA[Fills the slices between the drawn slices of a label map, "
    "every label at once, by level-set metamorphosis (lsmorph fill). Draw a few slices of "
    "each structure, leave the slices between empty, and run: the drawn slices come back "
    "exactly, each voxel between gets the label it lies deepest inside.]]></description>\n"
    "  <version>" LSM_VERSION "</version>\n"
    "  <documentation-url></documentation-url>\n"
    "  <license></license>\n"
    "  <contributor>lsmorph</contributor>\n"
    "  <acknowledgements></acknowledgements>\n"
    "  <parameters>\n"
    "    <label>Label maps</label>\n"
    "    <description>The drawn label map and the filled one</description>\n"
    "    <string hidden=\"true\">\n"
    "      <name>command</name>\n"
    "      <label>Command</label>\n"
    "      <description>lsmorph's command</description>\n"
    "      <index>0</index>\n"
    "      <default>fill</default>\n"
    "    </string>\n"
    "    <image type=\"label\">\n"
    "      <name>inputLabels</name>\n"
    "      <label>Drawn label map</label>\n"
    "      <description>Labels drawn on some slices, the slices between empty</description>\n"
    "      <channel>input</channel>\n"
    "      <index>1</index>\n"
    "    </image>\n"
    "    <image type=\"label\" reference=\"inputLabels\">\n"
    "      <name>outputLabels</name>\n"
    "      <label>Filled label map</label>\n"
    "      <description>The label map with the slices between the drawn ones filled</description>\n"
    "      <channel>output</channel>\n"
    "      <index>2</index>\n"
    "    </image>\n"
    "  </parameters>\n";

static const char fill_xml_slices[] =
    "  <parameters>\n"
    "    <label>Slices</label>\n"
    "    <description>Which slices were drawn, and which labels to fill</description>\n"
    ENUM("axis", "Slice axis",
         "The axis the drawn slices lie across (auto: the axis of the largest voxel spacing)",
         DEF("auto") EL("auto") EL("i") EL("j") EL("k"))
    "    <string>\n"
    "      <name>slices</name>\n"
    "      <longflag>slices</longflag>\n"
    "      <label>Drawn slices</label>\n"
    "      <description>Slice numbers from 0 (N, A:B, A:B:S, comma separated); empty: every "
    "slice holding a label, and one typical step beyond the first and the last</description>\n"
    "      <default></default>\n"
    "    </string>\n"
    "    <string>\n"
    "      <name>labels</name>\n"
    "      <longflag>labels</longflag>\n"
    "      <label>Labels</label>\n"
    "      <description>The labels to fill (comma separated); empty: every label</description>\n"
    "      <default></default>\n"
    "    </string>\n"
    "  </parameters>\n";

static const char fill_xml_method[] =
    "  <parameters advanced=\"true\">\n"
    "    <label>Method</label>\n"
    "    <description>How each label is interpolated between its drawn slices</description>\n"
    ENUM("method", "Method",
         "ls: level-set morph; pls: with particle correction; blend: linear blend of signed "
         "distances",
         DEF("ls") EL("ls") EL("pls") EL("blend"))
    ENUM("interp", "Profile across slices",
         "cubic: monotone cubic through the four nearest slices; linear: each gap alone",
         DEF("cubic") EL("cubic") EL("linear"))
    ENUM("ends", "Object ends",
         "halfway: an object ends at mid-gap; tip: a shrinking tip reaches the empty slice; "
         "auto: tip at the first and last slices only",
         DEF("halfway") EL("halfway") EL("tip") EL("auto"))
    ENUM("align", "Alignment", "Centroid alignment of sections that moved",
         DEF("auto") EL("auto") EL("hull") EL("none"))
    ENUM("motion", "Motion", "auto: per pair of drawn slices, the field where it predicts the "
         "drawn slices better when each is left out; field: parts that moved or turned off "
         "themselves follow a registration of the two slices (replaces auto alignment); "
         "none: in place",
         DEF("auto") EL("auto") EL("field") EL("none"))
    ENUM("scheme", "Scheme", "Numerical Hamiltonian", DEF("upwind") EL("upwind") EL("roe-fix")
         EL("weno5"))
    ENUM("time", "Time integrator", "Euler or TVD Runge-Kutta", DEF("euler") EL("euler") EL("rk2")
         EL("rk3"))
    "    <double>\n"
    "      <name>cfl</name>\n"
    "      <longflag>cfl</longflag>\n"
    "      <label>CFL number</label>\n"
    "      <description>Time step as a fraction of the stable one</description>\n"
    "      <default>0.75</default>\n"
    "      <constraints><minimum>0.05</minimum><maximum>1</maximum><step>0.05</step></constraints>\n"
    "    </double>\n"
    "  </parameters>\n";

static const char fill_xml_running[] =
    "  <parameters advanced=\"true\">\n"
    "    <label>Running</label>\n"
    "    <description>Threads and device</description>\n"
    "    <integer>\n"
    "      <name>threads</name>\n"
    "      <longflag>threads</longflag>\n"
    "      <label>Threads</label>\n"
    "      <description>0: all cores</description>\n"
    "      <default>0</default>\n"
    "      <constraints><minimum>0</minimum><maximum>4096</maximum><step>1</step></constraints>\n"
    "    </integer>\n"
    ENUM("backend", "Backend", "c: the reference; opencl: an OpenCL device; auto: OpenCL when present",
         DEF("c") EL("c") EL("opencl") EL("auto"))
    "  </parameters>\n"
    "</executable>\n";

void lsm_fill_xml(FILE *f) {
  fputs(fill_xml_head, f);
  fputs(fill_xml_slices, f);
  fputs(fill_xml_method, f);
  fputs(fill_xml_running, f);
}
