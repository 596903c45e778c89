/* io_labels_nrrd: NRRD label volumes through teem's nrrd (Debian libteem-dev):
 * .nrrd and .seg.nrrd with an attached header, .nhdr with a detached one,
 * any encoding teem reads (raw, gzip, bzip2, ascii, hex).
 *
 * A file is read twice: the header alone first (nio->skipData), checked
 * before any voxel is allocated, then whole.  Written, the header is teem's
 * (every field, comment and key/value pair of the input) through nrrdWrite
 * into a stream lsmorph opened and closes with checks; a detached header's
 * samples are written by lsmorph (raw or gzip), its data file renamed into
 * place before the header.  Compressed input gives gzip output, raw gives raw.
 *
 * 3D Slicer's .seg.nrrd: a 4D file with one layer (the first axis of size 1)
 * is read as its 3D volume and written back 4D; several layers (segments that
 * overlap) are refused.  Segment names, colours and label values are
 * key/value pairs and come back unchanged; SegmentN_Extent, the box of
 * segment N's voxels, is set to the filled segment's. */
#include "io/io_labels_impl.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <teem/nrrd.h>

#include "io/lsm_io.h"

static Nrrd *nrrd_of(const lsm_label_file *f) { return (Nrrd *)f->native; }

/* Read by LeakSanitizer (make SANITIZE=1, fuzzing): teem 1.12 leaks on the error
 * paths of its parser and gzip reader, and its bzip2 reader leaks libbz2's stream
 * (a damaged file, which lsmorph refuses; lsmorph itself does not call libbz2);
 * lsmorph frees every teem object it holds with nrrdNuke/nrrdNix.  Only in
 * ASan builds, and visible: the runtime looks it up dynamically. */
#ifdef __has_feature
#if __has_feature(address_sanitizer)
#define LSM_ASAN 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(LSM_ASAN)
__attribute__((visibility("default"))) const char *__lsan_default_suppressions(void);
const char *__lsan_default_suppressions(void) { return "leak:libteem.so\nleak:libbz2.so\n"; }
#endif

/* teem's message (biff) for what failed: the innermost cause, without the
 * "[nrrd] function: " prefixes. */
static lsm_status teem_fail(lsm_err *err, lsm_status status, const char *where, const char *what) {
  char *msg = biffGetDone(NRRD);
  const char *cause = "";
  if (msg) {
    size_t len = strlen(msg);
    while (len > 0 && (msg[len - 1] == '\n' || msg[len - 1] == ' ')) msg[--len] = '\0';
    const char *line = strrchr(msg, '\n');
    cause = line ? line + 1 : msg;
    if (strncmp(cause, "[nrrd] ", 7) == 0) cause += 7;
    const char *colon = strstr(cause, ": ");
    if (colon && !memchr(cause, ' ', (size_t)(colon - cause))) cause = colon + 2;
  }
  lsm_fail(err, status, where, "%s%s%s", what, *cause ? ": " : "", cause);
  free(msg);
  return status;
}

static lsm_voxel_type voxel_type_of(int type) {
  switch (type) {
  case nrrdTypeChar: return LSM_VOXEL_I8;
  case nrrdTypeUChar: return LSM_VOXEL_U8;
  case nrrdTypeShort: return LSM_VOXEL_I16;
  case nrrdTypeUShort: return LSM_VOXEL_U16;
  case nrrdTypeInt: return LSM_VOXEL_I32;
  case nrrdTypeUInt: return LSM_VOXEL_U32;
  case nrrdTypeLLong: return LSM_VOXEL_I64;
  case nrrdTypeULLong: return LSM_VOXEL_U64;
  case nrrdTypeFloat: return LSM_VOXEL_F32;
  case nrrdTypeDouble: return LSM_VOXEL_F64;
  default: return LSM_VOXEL_UNKNOWN;
  }
}

static int nrrd_type_of(lsm_voxel_type type) {
  static const int codes[] = {nrrdTypeUChar,  nrrdTypeChar,  nrrdTypeUShort, nrrdTypeShort,
                              nrrdTypeUInt,   nrrdTypeInt,   nrrdTypeULLong, nrrdTypeLLong,
                              nrrdTypeFloat,  nrrdTypeDouble};
  return (int)type >= 0 && (int)type < (int)(sizeof codes / sizeof *codes) ? codes[type]
                                                                           : nrrdTypeUnknown;
}

/* The first axis of the volume: 1 in a one-layer 4D .seg.nrrd, else 0. */
static unsigned first_axis(const Nrrd *nrrd) { return nrrd->dim == 4 ? 1u : 0u; }

/* Checks what the header says before the samples are read. */
static lsm_status check_header(lsm_label_file *f, const Nrrd *nrrd, uint64_t max_voxels,
                               lsm_err *err) {
  if (nrrd->dim == 4 && nrrd->axis[0].size > 1)
    return lsm_fail(err, LSM_ERR_INPUT, f->path,
                    "a 4D volume of %zu layers%s: a label map is 3D (in 3D Slicer, export the "
                    "segmentation as a labelmap volume, or make its segments not overlap so "
                    "that it is saved as one layer)",
                    nrrd->axis[0].size,
                    lsm_labels_ends_with(f->path, ".seg.nrrd")
                        ? " (a segmentation whose segments overlap, stored in layers)"
                        : "");
  if (nrrd->dim != 3 && nrrd->dim != 4)
    return lsm_fail(err, LSM_ERR_INPUT, f->path, "a %u-dimensional image: a label volume is 3D",
                    nrrd->dim);
  const lsm_voxel_type type = voxel_type_of(nrrd->type);
  if (type == LSM_VOXEL_UNKNOWN)
    return lsm_fail(err, LSM_ERR_INPUT, f->path,
                    "not a label map: its samples are of type %s (labels are integers, or "
                    "floats holding whole numbers)",
                    airEnumStr(nrrdType, nrrd->type));
  const unsigned a0 = first_axis(nrrd);
  for (unsigned a = 0; a < 3; ++a) f->vox.n[a] = nrrd->axis[a0 + a].size;
  return lsm_labels_sized(f, type, max_voxels, err);
}

/* Index to LPS world from the space directions and origin, else the
 * spacings (and axis mins) on the diagonal. */
static void lps_affine(const Nrrd *nrrd, double m[3][4]) {
  const unsigned a0 = first_axis(nrrd);
  memset(m, 0, 12 * sizeof(double));
  if (nrrd->spaceDim == 3) {
    for (int a = 0; a < 3; ++a)
      for (int r = 0; r < 3; ++r) m[r][a] = nrrd->axis[a0 + (unsigned)a].spaceDirection[r];
    for (int r = 0; r < 3; ++r) m[r][3] = isfinite(nrrd->spaceOrigin[r]) ? nrrd->spaceOrigin[r] : 0.0;
    /* RAS and LAS flip to LPS; LPS, scanner-xyz and 3D-right-handed are taken as LPS */
    const int flip_x = nrrd->space == nrrdSpaceRightAnteriorSuperior;
    const int flip_y = flip_x || nrrd->space == nrrdSpaceLeftAnteriorSuperior;
    for (int c = 0; c < 4; ++c) {
      if (flip_x) m[0][c] = 0.0 - m[0][c];
      if (flip_y) m[1][c] = 0.0 - m[1][c];
    }
    return;
  }
  for (int a = 0; a < 3; ++a) {
    const NrrdAxisInfo *ax = &nrrd->axis[a0 + (unsigned)a];
    m[a][a] = isfinite(ax->spacing) ? ax->spacing : 1.0;
    m[a][3] = isfinite(ax->min) ? ax->min : 0.0;
  }
}

/* Calls visit on each data file a header names that exists: its lines up to
 * the first blank one are scanned for "data file: NAME" or "data file: LIST"
 * and the names after it (header-relative unless absolute), as teem reads
 * them; "-" (standard input, where teem would wait) is refused; the format
 * form ("NAME%03d.raw MIN MAX STEP") is left to teem. */
typedef lsm_status (*data_file_visit)(const char *header, const char *data, const struct stat *sb,
                                      const void *ctx, lsm_err *err);
static lsm_status each_data_file(const char *header, data_file_visit visit, const void *ctx,
                                 lsm_err *err) {
  FILE *fp = fopen(header, "rb");
  if (!fp) return LSM_OK; /* teem says why */
  char text[1 << 16];
  const size_t got = fread(text, 1, sizeof text - 1, fp);
  fclose(fp);
  text[got] = '\0';
  const char *slash = strrchr(header, '/');
  const int dir_len = slash ? (int)(slash - header) : 0;
  int list = 0;
  for (char *line = text, *next; line && *line; line = next) {
    next = strchr(line, '\n');
    if (next) *next++ = '\0';
    const size_t len = strlen(line);
    if (len && line[len - 1] == '\r') line[len - 1] = '\0';
    if (!list && !*line) break; /* the end of the header */
    const char *name = line;
    if (!list) {
      const char *colon = NULL;
      if (strncmp(line, "data file:", 10) == 0) colon = line + 9;
      else if (strncmp(line, "datafile:", 9) == 0) colon = line + 8;
      if (!colon) continue;
      name = colon + 1 + strspn(colon + 1, " \t");
      if (strncmp(name, "LIST", 4) == 0) {
        list = 1;
        continue;
      }
      if (strchr(name, ' ')) break; /* the format form */
    }
    if (!*name) continue;
    if (strcmp(name, "-") == 0) /* teem would wait on standard input */
      return lsm_fail(err, LSM_ERR_INPUT, header,
                      "its data file is '-' (standard input), which lsmorph does not read: "
                      "name the data file");
    char path[4200];
    const int n = name[0] == '/' || !slash
                      ? snprintf(path, sizeof path, "%s", name)
                      : snprintf(path, sizeof path, "%.*s/%s", dir_len, header, name);
    struct stat sb;
    if (n > 0 && (size_t)n < sizeof path && stat(path, &sb) == 0)
      LSM_TRY(visit(header, path, &sb, ctx, err));
    if (!list) break;
  }
  return LSM_OK;
}

/* A pipe or a device would block the read (teem opens data files even for the
 * header alone) or be read twice; a folder reads as empty. */
static lsm_status refuse_irregular(const char *header, const char *data, const struct stat *sb,
                                   const void *ctx, lsm_err *err) {
  (void)ctx;
  if (S_ISREG(sb->st_mode)) return LSM_OK;
  return lsm_fail(err, LSM_ERR_INPUT, header,
                  "its data file %s is not a regular file (a folder, a pipe or a device)", data);
}

/* ctx: the stat of an output data file. */
static lsm_status refuse_same(const char *header, const char *data, const struct stat *sb,
                              const void *ctx, lsm_err *err) {
  const struct stat *out = ctx;
  (void)header;
  if (sb->st_dev != out->st_dev || sb->st_ino != out->st_ino) return LSM_OK;
  return lsm_fail(err, LSM_ERR_INPUT, data,
                  "is the input's data file: write the result under another name (the drawn "
                  "slices would be lost)");
}

lsm_status lsm_nrrd_labels_check_data_output(const char *input, const char *data_out,
                                             lsm_err *err) {
  struct stat out;
  if (stat(data_out, &out) != 0) return LSM_OK;
  return each_data_file(input, refuse_same, &out, err);
}

lsm_status lsm_nrrd_labels_read(lsm_label_file *f, uint64_t max_voxels, lsm_err *err) {
  nrrdStateVerboseIO = 0; /* teem's progress lines on stderr */
  /* teem also reads PNG, PNM, VTK and plain text: only NRRD is taken here */
  FILE *probe = fopen(f->path, "rb");
  char magic[8] = {0};
  const size_t got = probe ? fread(magic, 1, sizeof magic, probe) : 0;
  if (probe) fclose(probe);
  if (got < 8 || memcmp(magic, "NRRD000", 7) != 0 || magic[7] < '1' || magic[7] > '9')
    return lsm_fail(err, LSM_ERR_INPUT, f->path, "cannot read: not a NRRD file (no NRRD000N magic)");
  LSM_TRY(each_data_file(f->path, refuse_irregular, NULL, err));
  Nrrd *head = nrrdNew();
  NrrdIoState *nio = nrrdIoStateNew();
  if (!head || !nio) {
    nrrdNuke(head);
    nrrdIoStateNix(nio);
    return lsm_fail(err, LSM_ERR_NOMEM, f->path, "cannot allocate the header");
  }
  nio->skipData = 1;
  lsm_status st = LSM_OK;
  if (nrrdLoad(head, f->path, nio) != 0)
    st = teem_fail(err, LSM_ERR_INPUT, f->path, "cannot read the header");
  if (st == LSM_OK) st = check_header(f, head, max_voxels, err);
  /* teem skips bytes inside a bzip2 stream without closing it when it fails (a leak) */
  if (st == LSM_OK && nio->encoding == nrrdEncodingBzip2 && nio->byteSkip != 0)
    st = lsm_fail(err, LSM_ERR_INPUT, f->path,
                  "cannot read: 'byte skip' inside bzip2-encoded data is not supported (save it "
                  "without byte skip, or gzip- or raw-encoded)");
  nrrdNuke(head);
  nrrdIoStateNix(nio);
  if (st != LSM_OK) return st;
  Nrrd *nrrd = nrrdNew();
  nio = nrrdIoStateNew();
  if (!nrrd || !nio) {
    nrrdNuke(nrrd);
    nrrdIoStateNix(nio);
    return lsm_fail(err, LSM_ERR_NOMEM, f->path, "cannot allocate the header");
  }
  f->native = nrrd;
  if (nrrdLoad(nrrd, f->path, nio) != 0)
    st = teem_fail(err, LSM_ERR_INPUT, f->path, "cannot read");
  /* the same header as checked (the file could have changed in between) */
  if (st == LSM_OK) {
    const size_t n[3] = {f->vox.n[0], f->vox.n[1], f->vox.n[2]};
    const lsm_voxel_type type = f->vox.type;
    st = check_header(f, nrrd, max_voxels, err);
    if (st == LSM_OK && (memcmp(n, f->vox.n, sizeof n) != 0 || type != f->vox.type || !nrrd->data))
      st = lsm_fail(err, LSM_ERR_INPUT, f->path, "changed while it was read");
  }
  if (st == LSM_OK) {
    f->vox.data = nrrd->data;
    f->compressed = nio->encoding != nrrdEncodingRaw;
    lps_affine(nrrd, f->affine);
  }
  /* lsmorph's own notes travel to an output of the other format too */
  for (unsigned k = 0; st == LSM_OK && k < nrrd->kvpArr->len; ++k)
    if (strncmp(nrrd->kvp[2 * k], "lsmorph", 7) == 0 && f->notes < LSM_LABELS_NOTES_MAX)
      st = lsm_labels_set_note(f, nrrd->kvp[2 * k], nrrd->kvp[2 * k + 1], err);
  nrrdIoStateNix(nio);
  return st;
}

void lsm_nrrd_labels_adopt(lsm_label_file *f, void *old_data) {
  Nrrd *nrrd = nrrd_of(f);
  free(old_data);
  nrrd->data = f->vox.data;
  nrrd->type = nrrd_type_of(f->vox.type);
}

void lsm_nrrd_labels_free(lsm_label_file *f) {
  nrrdNuke(nrrd_of(f));
  f->native = NULL;
  f->vox.data = NULL;
}

/* ---- notes: key/value pairs --------------------------------------------------------------- */

const char *lsm_nrrd_labels_note(const lsm_label_file *f, const char *key) {
  const Nrrd *nrrd = nrrd_of(f);
  for (unsigned k = 0; k < nrrd->kvpArr->len; ++k)
    if (strcmp(nrrd->kvp[2 * k], key) == 0) return nrrd->kvp[2 * k + 1];
  return NULL;
}

/* ---- 3D Slicer's segment extents ------------------------------------------------------------ */

typedef struct segment_box {
  int64_t value;
  unsigned kv;       /* index of its SegmentN_Extent pair, or UINT_MAX */
  size_t lo[3], hi[3];
  int seen;
} segment_box;

static int cmp_box(const void *a, const void *b) {
  const int64_t x = ((const segment_box *)a)->value, y = ((const segment_box *)b)->value;
  return (x > y) - (x < y);
}

/* SegmentN_Extent of every segment whose SegmentN_LabelValue is given (in
 * layer 0, the only one) becomes the box of its voxels ("0 -1 0 -1 0 -1"
 * when it has none), as 3D Slicer writes it. */
static lsm_status update_extents(lsm_label_file *f, lsm_err *err) {
  Nrrd *nrrd = nrrd_of(f);
  const unsigned pairs = nrrd->kvpArr->len;
  segment_box *box = calloc(pairs ? pairs : 1, sizeof *box);
  if (!box) return lsm_fail(err, LSM_ERR_NOMEM, f->path, "cannot allocate the segment boxes");
  size_t nbox = 0;
  for (unsigned k = 0; k < pairs; ++k) {
    const char *key = nrrd->kvp[2 * k];
    int n = 0, used = 0;
    if (sscanf(key, "Segment%d_LabelValue%n", &n, &used) != 1 || key[used] != '\0') continue;
    char extent[64];
    snprintf(extent, sizeof extent, "Segment%d_Extent", n);
    char *end = NULL;
    const long long value = strtoll(nrrd->kvp[2 * k + 1], &end, 10);
    if (!end || *end) continue;
    for (unsigned q = 0; q < pairs; ++q)
      if (strcmp(nrrd->kvp[2 * q], extent) == 0) {
        box[nbox].value = value;
        box[nbox].kv = q;
        nbox++;
      }
  }
  if (nbox) {
    qsort(box, nbox, sizeof *box, cmp_box);
    const lsm_voxels *v = &f->vox;
    size_t at = 0;
    for (size_t kk = 0; kk < v->n[2]; ++kk)
      for (size_t j = 0; j < v->n[1]; ++j)
        for (size_t i = 0; i < v->n[0]; ++i, ++at) {
          const int64_t value = lsm_voxel_get_int(v, at);
          if (value == 0) continue;
          size_t lo = 0, hi = nbox;
          while (lo < hi) { /* the first box of this value */
            const size_t mid = (lo + hi) / 2;
            if (box[mid].value < value) lo = mid + 1; else hi = mid;
          }
          for (size_t b = lo; b < nbox && box[b].value == value; ++b) {
            const size_t ijk[3] = {i, j, kk};
            for (int a = 0; a < 3; ++a) {
              if (!box[b].seen || ijk[a] < box[b].lo[a]) box[b].lo[a] = ijk[a];
              if (!box[b].seen || ijk[a] > box[b].hi[a]) box[b].hi[a] = ijk[a];
            }
            box[b].seen = 1;
          }
        }
  }
  lsm_status st = LSM_OK;
  for (size_t b = 0; b < nbox && st == LSM_OK; ++b) {
    char text[160];
    if (box[b].seen)
      snprintf(text, sizeof text, "%zu %zu %zu %zu %zu %zu", box[b].lo[0], box[b].hi[0],
               box[b].lo[1], box[b].hi[1], box[b].lo[2], box[b].hi[2]);
    else
      snprintf(text, sizeof text, "0 -1 0 -1 0 -1");
    char *copy = airStrdup(text);
    if (!copy) st = lsm_fail(err, LSM_ERR_NOMEM, f->path, "cannot set a segment extent");
    else {
      free(nrrd->kvp[2 * box[b].kv + 1]);
      nrrd->kvp[2 * box[b].kv + 1] = copy;
    }
  }
  free(box);
  return st;
}

/* ---- writing ------------------------------------------------------------------------------ */

/* A header for f's voxels when f was read from a NIfTI file: LPS space,
 * directions and origin from the affine, millimetres.  Its data is f's. */
static Nrrd *new_header(const lsm_label_file *f) {
  Nrrd *nrrd = nrrdNew();
  const size_t sizes[3] = {f->vox.n[0], f->vox.n[1], f->vox.n[2]};
  if (!nrrd || nrrdWrap_nva(nrrd, f->vox.data, nrrd_type_of(f->vox.type), 3, sizes) != 0 ||
      nrrdSpaceSet(nrrd, nrrdSpaceLeftPosteriorSuperior) != 0) {
    if (nrrd) nrrdNix(nrrd);
    return NULL;
  }
  const double origin[3] = {f->affine[0][3], f->affine[1][3], f->affine[2][3]};
  nrrdSpaceOriginSet(nrrd, origin);
  for (unsigned a = 0; a < 3; ++a) {
    for (int r = 0; r < 3; ++r) nrrd->axis[a].spaceDirection[r] = f->affine[r][a];
    nrrd->axis[a].kind = nrrdKindDomain;
  }
  for (int r = 0; r < 3; ++r) nrrd->spaceUnits[r] = airStrdup("mm");
  return nrrd;
}

lsm_status lsm_nrrd_labels_write(lsm_label_file *f, int fd, const char *tmp, int data_fd,
                                 const char *data_tmp, const char *data_name, const char *path,
                                 lsm_err *err) {
  nrrdStateVerboseIO = 0;
  const int own = f->format != LSM_LABELS_NRRD;
  Nrrd *nrrd = own ? new_header(f) : nrrd_of(f);
  NrrdIoState *nio = nrrdIoStateNew();
  FILE *fp = fdopen(fd, "wb");
  lsm_status st = LSM_OK;
  if (!fp) {
    close(fd);
    st = lsm_fail(err, LSM_ERR_IO, tmp, "cannot write");
  }
  if (st == LSM_OK && (!nrrd || !nio))
    st = lsm_fail(err, LSM_ERR_NOMEM, path, "cannot make a NRRD header");
  if (st == LSM_OK && !own) {
    nrrd->data = f->vox.data;
    nrrd->type = nrrd_type_of(f->vox.type);
    st = update_extents(f, err);
  }
  for (int k = 0; st == LSM_OK && k < f->notes; ++k)
    if (nrrdKeyValueAdd(nrrd, f->note_key[k], f->note_text[k]) != 0)
      st = teem_fail(err, LSM_ERR_NOMEM, path, "cannot add a key/value pair");
  const int gz = f->compressed && nrrdEncodingGzip->available();
  if (st == LSM_OK) {
    nio->encoding = gz ? nrrdEncodingGzip : nrrdEncodingRaw;
    nio->skipFormatURL = 1;
    if (data_fd >= 0) { /* the header names the data file; lsmorph writes it */
      nio->detachedHeader = 1;
      nio->skipData = 1;
      const unsigned slot = airArrayLenIncr(nio->dataFNArr, 1);
      if (!nio->dataFN || !(nio->dataFN[slot] = airStrdup(data_name)))
        st = lsm_fail(err, LSM_ERR_NOMEM, path, "cannot name the data file");
    }
  }
  if (st == LSM_OK && nrrdWrite(fp, nrrd, nio) != 0)
    st = teem_fail(err, LSM_ERR_IO, path, "cannot write");
  st = lsm_close_written(&fp, tmp, st, err);
  if (data_fd >= 0) {
    lsm_labels_sink sink;
    lsm_status ds = lsm_labels_sink_open(&sink, data_fd, gz, data_tmp, err);
    size_t count = 0;
    if (ds == LSM_OK && st == LSM_OK) {
      ds = lsm_voxels_count(f->vox.n, f->vox.type, &count, path, err);
      if (ds == LSM_OK)
        ds = lsm_labels_sink_write(&sink, f->vox.data, count * lsm_voxel_size(f->vox.type), err);
    }
    if (ds == LSM_OK || sink.fp || sink.gz) ds = lsm_labels_sink_close(&sink, ds, err);
    if (st == LSM_OK) st = ds;
  }
  nrrdIoStateNix(nio);
  if (own && nrrd) nrrdNix(nrrd); /* the header, not f's voxels */
  return st;
}
