/* Tests of io/lsm_labels (label volumes: NRRD through teem, NIfTI through
 * nifticlib): round trips of values, geometry, key/value pairs and notes,
 * the integer conversion, the output checks, and hostile headers refused
 * with a message (never a crash).  tests/test_fill.sh reads what lsmorph
 * writes with nibabel and VTK. */
#include "lsm_test.h"

#include <dirent.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <nifti1.h>

#include "io/lsm_labels.h"
#include "io/lsm_temp.h"

typedef struct tmp_fixture {
  char dir[64];
} tmp_fixture;

static int setup(void **state) {
  tmp_fixture *f = calloc(1, sizeof *f);
  snprintf(f->dir, sizeof f->dir, "/tmp/lsm_labels_XXXXXX");
  if (!mkdtemp(f->dir)) return -1;
  *state = f;
  return 0;
}

static int teardown(void **state) {
  tmp_fixture *f = *state;
  DIR *d = opendir(f->dir);
  struct dirent *e;
  while (d && (e = readdir(d)) != NULL) {
    char p[512];
    snprintf(p, sizeof p, "%s/%s", f->dir, e->d_name);
    if (e->d_name[0] != '.' || (e->d_name[1] && strcmp(e->d_name, "..") != 0)) unlink(p);
  }
  if (d) closedir(d);
  rmdir(f->dir);
  free(f);
  return 0;
}

static void path_in(const tmp_fixture *f, const char *name, char *out) {
  snprintf(out, 256, "%s/%s", f->dir, name);
}

/* Writes a NRRD file: header lines (without the blank line) and the data. */
static void write_nrrd(const char *path, const char *header, const void *data, size_t bytes) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  fputs(header, fp);
  fputs("\n", fp);
  if (bytes) assert_int_equal(fwrite(data, 1, bytes, fp), bytes);
  assert_int_equal(fclose(fp), 0);
}

static char *read_text(const char *path) {
  FILE *fp = fopen(path, "rb");
  assert_non_null(fp);
  char *buf = calloc(1, 1 << 16);
  size_t n = fread(buf, 1, (1 << 16) - 1, fp);
  buf[n] = '\0';
  fclose(fp);
  return buf;
}

/* The files of a folder whose names start with '.' and hold ".tmp-": left-over temporaries. */
static int temporaries(const char *dir) {
  DIR *d = opendir(dir);
  int n = 0;
  struct dirent *e;
  while (d && (e = readdir(d)) != NULL) n += e->d_name[0] == '.' && strstr(e->d_name, ".tmp-") != NULL;
  if (d) closedir(d);
  return n;
}

#define HEADER_4x3x2(type)                                                              \
  "NRRD0004\n# a test volume\ntype: " type "\ndimension: 3\nspace: left-posterior-superior\n" \
  "sizes: 4 3 2\nspace directions: (0.5,0,0) (0,0.8,0.1) (0,0,2.5)\nkinds: domain domain domain\n" \
  "endian: little\nencoding: raw\nspace origin: (10,-20,30)\n"

static const uint16_t values_4x3x2[24] = {0, 5, 5, 0, 0, 7, 0, 0, 0, 0, 0, 300,
                                          5, 5, 0, 0, 0, 0, 7, 7, 0, 0, 0, 0};

static void read_ok(const char *path, lsm_label_file **f) {
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_labels_read(path, 0, f, &err) != LSM_OK) fail_msg("%s", err.msg);
}

static void test_nrrd_round_trip(void **state) {
  tmp_fixture *fx = *state;
  char in[256], out[256], back[256];
  path_in(fx, "in.seg.nrrd", in);
  path_in(fx, "out.seg.nrrd", out);
  write_nrrd(in, HEADER_4x3x2("ushort") "Segment0_Name:=liver\nSegment0_Color:=0.5 0.2 0.1\n"
                                        "Segment0_LabelValue:=5\nSegment0_Extent:=0 0 0 0 0 0\n",
             values_4x3x2, sizeof values_4x3x2);
  lsm_label_file *f = NULL;
  read_ok(in, &f);
  lsm_voxels *v = lsm_labels_voxels(f);
  assert_int_equal(v->n[0], 4);
  assert_int_equal(v->n[1], 3);
  assert_int_equal(v->n[2], 2);
  assert_int_equal(v->type, LSM_VOXEL_U16);
  assert_memory_equal(v->data, values_4x3x2, sizeof values_4x3x2);
  assert_close(v->spacing[0], 0.5, 1e-12);
  assert_close(v->spacing[1], sqrt(0.64 + 0.01), 1e-12);
  double m[3][4];
  lsm_labels_affine(f, m);
  assert_close(m[1][1], 0.8, 1e-12);
  assert_close(m[2][1], 0.1, 1e-12);
  assert_close(m[1][3], -20.0, 1e-12);
  double cosine = 0;
  lsm_labels_axes_cosine(f, &cosine);
  assert_true(cosine > 0.01); /* j and k are not at right angles */
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_labels_set_note(f, "lsmorph_fill", "axis=k drawn=0,1", &err), LSM_OK);
  ((uint16_t *)v->data)[0] = 5; /* segment 5: (0 1 2, 0, 0) and (0 1, 0, 1) */
  assert_int_equal(lsm_labels_write(f, out, &err), LSM_OK);
  assert_int_equal(temporaries(fx->dir), 0);
  char *text = read_text(out);
  assert_non_null(strstr(text, "Segment0_Name:=liver"));
  assert_non_null(strstr(text, "Segment0_Color:=0.5 0.2 0.1"));
  assert_non_null(strstr(text, "Segment0_Extent:=0 2 0 0 0 1"));
  assert_non_null(strstr(text, "# a test volume"));
  assert_non_null(strstr(text, "lsmorph_fill:=axis=k drawn=0,1"));
  free(text);
  lsm_label_file *g = NULL;
  read_ok(out, &g);
  assert_memory_equal(lsm_labels_voxels(g)->data, v->data, sizeof values_4x3x2);
  assert_string_equal(lsm_labels_note(g, "lsmorph_fill"), "axis=k drawn=0,1");
  /* to NIfTI and back: the same voxels and world geometry */
  path_in(fx, "x.nii.gz", back);
  assert_int_equal(lsm_labels_write(g, back, &err), LSM_OK);
  lsm_label_file *h = NULL;
  read_ok(back, &h);
  assert_memory_equal(lsm_labels_voxels(h)->data, v->data, sizeof values_4x3x2);
  assert_string_equal(lsm_labels_note(h, "lsmorph_fill"), "axis=k drawn=0,1");
  double mh[3][4];
  lsm_labels_affine(h, mh);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) assert_close(mh[r][c], m[r][c], 1e-5 * (1 + fabs(m[r][c])));
  path_in(fx, "y.nrrd", back);
  assert_int_equal(lsm_labels_write(h, back, &err), LSM_OK);
  lsm_labels_free(&h);
  read_ok(back, &h);
  lsm_labels_affine(h, mh);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) assert_close(mh[r][c], m[r][c], 1e-5 * (1 + fabs(m[r][c])));
  lsm_labels_free(&h);
  lsm_labels_free(&g);
  lsm_labels_free(&f);
}

static void test_nrrd_detached_gzip(void **state) {
  tmp_fixture *fx = *state;
  char hdr[256], data[256], out[256], out_data[256];
  path_in(fx, "d.nhdr", hdr);
  path_in(fx, "d.raw.gz", data);
  gzFile gz = gzopen(data, "wb");
  assert_non_null(gz);
  assert_int_equal(gzwrite(gz, values_4x3x2, sizeof values_4x3x2), (int)sizeof values_4x3x2);
  assert_int_equal(gzclose(gz), Z_OK);
  FILE *fp = fopen(hdr, "w");
  fputs("NRRD0004\ntype: uint16\ndimension: 3\nsizes: 4 3 2\nspacings: 1 2 3\nendian: little\n"
        "encoding: gzip\ndata file: d.raw.gz\n", fp);
  fclose(fp);
  lsm_label_file *f = NULL;
  read_ok(hdr, &f);
  assert_memory_equal(lsm_labels_voxels(f)->data, values_4x3x2, sizeof values_4x3x2);
  assert_close(lsm_labels_voxels(f)->spacing[2], 3.0, 1e-12);
  path_in(fx, "o.nhdr", out);
  path_in(fx, "o.raw.gz", out_data);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_labels_write(f, out, &err), LSM_OK);
  struct stat sb;
  assert_int_equal(stat(out_data, &sb), 0); /* gzip in, gzip out, beside the header */
  assert_int_equal(temporaries(fx->dir), 0);
  char *text = read_text(out);
  assert_non_null(strstr(text, "o.raw.gz\n"));
  free(text);
  lsm_label_file *g = NULL;
  read_ok(out, &g);
  assert_memory_equal(lsm_labels_voxels(g)->data, values_4x3x2, sizeof values_4x3x2);
  lsm_labels_free(&g);
  lsm_labels_free(&f);
}

static void test_float_labels(void **state) {
  tmp_fixture *fx = *state;
  char path[256];
  path_in(fx, "f.nrrd", path);
  float v[24];
  for (int k = 0; k < 24; ++k) v[k] = k % 5 == 0 ? -3.0f : (float)(k * 20);
  write_nrrd(path, HEADER_4x3x2("float"), v, sizeof v);
  lsm_label_file *f = NULL;
  read_ok(path, &f);
  lsm_err err;
  lsm_err_clear(&err);
  int converted = 0;
  assert_int_equal(lsm_labels_to_integer(f, &converted, &err), LSM_OK);
  assert_int_equal(converted, 1);
  lsm_voxels *vox = lsm_labels_voxels(f);
  assert_int_equal(vox->type, LSM_VOXEL_I16); /* -3 .. 460 */
  for (int k = 0; k < 24; ++k) assert_int_equal(lsm_voxel_get_int(vox, (size_t)k), (int64_t)v[k]);
  lsm_labels_free(&f);
  v[7] = 2.5f;
  write_nrrd(path, HEADER_4x3x2("float"), v, sizeof v);
  read_ok(path, &f);
  assert_int_equal(lsm_labels_to_integer(f, &converted, &err), LSM_ERR_INPUT);
  assert_non_null(strstr(err.msg, "not a label map: voxel (3, 1, 0) holds 2.5"));
  lsm_labels_free(&f);
}

/* Each header must be refused with a message naming the file and saying `what`. */
static void expect_refused(const char *path, const char *what, uint64_t max_voxels) {
  lsm_label_file *f = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  const lsm_status st = lsm_labels_read(path, max_voxels, &f, &err);
  if (st == LSM_OK) {
    int converted = 0;
    if (lsm_labels_to_integer(f, &converted, &err) == LSM_OK)
      fail_msg("%s was accepted (wanted: %s)", path, what);
  }
  assert_null(st == LSM_OK ? NULL : f);
  lsm_labels_free(&f);
  if (strncmp(err.msg, path, strlen(path)) != 0 || !strstr(err.msg, what))
    fail_msg("%s: message '%s' does not say '%s'", path, err.msg, what);
}

static void test_hostile_nrrd(void **state) {
  tmp_fixture *fx = *state;
  char p[256];
  path_in(fx, "h.nrrd", p);
  static const char base[] = "NRRD0004\ntype: uchar\ndimension: 3\nendian: little\nencoding: raw\n";
  char header[512];
  uint8_t bytes[64] = {0};
  snprintf(header, sizeof header, "%ssizes: 4294967296 4294967296 4294967296\n", base);
  write_nrrd(p, header, bytes, sizeof bytes);
  expect_refused(p, "", 0);
  snprintf(header, sizeof header, "%ssizes: 0 3 2\n", base);
  write_nrrd(p, header, bytes, sizeof bytes);
  expect_refused(p, "", 0);
  snprintf(header, sizeof header, "%ssizes: 100 100 100\n", base);
  write_nrrd(p, header, bytes, sizeof bytes);
  expect_refused(p, "more than --max-voxels 1000", 1000);
  expect_refused(p, "cannot read", 0); /* 64 bytes of a million */
  write_nrrd(p, "NRRD0004\ntype: uchar\ndimension: 2\nsizes: 4 4\nencoding: raw\n", bytes, 16);
  expect_refused(p, "a 2-dimensional image", 0);
  write_nrrd(p, "NRRD0004\ntype: block\nblock size: 2\ndimension: 3\nsizes: 2 2 2\nendian: little\n"
                "encoding: raw\n",
             bytes, 16);
  expect_refused(p, "not a label map", 0);
  write_nrrd(p, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 2\nencoding: gzip\n", "garbage!",
             8);
  expect_refused(p, "cannot read", 0);
  write_nrrd(p, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nspace dimension: 3\n"
                "space directions: (0,0,0) (0,1,0) (0,0,1)\nencoding: raw\n", bytes, 8);
  expect_refused(p, "spacing along i is 0", 0);
  path_in(fx, "layers.seg.nrrd", p);
  write_nrrd(p, "NRRD0004\ntype: uchar\ndimension: 4\nsizes: 2 2 2 2\nkinds: list domain domain "
                "domain\nencoding: raw\n", bytes, 16);
  expect_refused(p, "export the segmentation as a labelmap", 0);
  path_in(fx, "text.nrrd", p);
  write_nrrd(p, "1 2 3\n4 5 6", NULL, 0); /* teem would read it as a text array */
  expect_refused(p, "not a NRRD file", 0);
  path_in(fx, "missing.nrrd", p);
  expect_refused(p, "cannot read", 0);
}

static void write_nifti(const char *path, const nifti_1_header *h, const void *data, size_t bytes) {
  FILE *fp = fopen(path, "wb");
  assert_non_null(fp);
  assert_int_equal(fwrite(h, sizeof *h, 1, fp), 1);
  const char ext[4] = {0, 0, 0, 0};
  fwrite(ext, 1, 4, fp);
  if (bytes) fwrite(data, 1, bytes, fp);
  fclose(fp);
}

static void test_nifti(void **state) {
  tmp_fixture *fx = *state;
  char p[256], out[256];
  path_in(fx, "n.nii", p);
  nifti_1_header h;
  memset(&h, 0, sizeof h);
  h.sizeof_hdr = 348;
  h.dim[0] = 4; /* one time point: read as 3D */
  h.dim[1] = 4;
  h.dim[2] = 3;
  h.dim[3] = 2;
  h.dim[4] = 1;
  h.datatype = DT_UINT16;
  h.bitpix = 16;
  h.pixdim[1] = 0.5f;
  h.pixdim[2] = 0.8f;
  h.pixdim[3] = 2.5f;
  h.vox_offset = 352;
  h.sform_code = 1;
  h.srow_x[0] = -0.5f; h.srow_x[3] = 10.0f;
  h.srow_y[1] = -0.8f; h.srow_y[3] = 20.0f;
  h.srow_z[2] = 2.5f; h.srow_z[3] = 30.0f;
  strcpy(h.descrip, "drawn by hand");
  memcpy(h.magic, "n+1", 4);
  write_nifti(p, &h, values_4x3x2, sizeof values_4x3x2);
  lsm_label_file *f = NULL;
  read_ok(p, &f);
  assert_memory_equal(lsm_labels_voxels(f)->data, values_4x3x2, sizeof values_4x3x2);
  double m[3][4];
  lsm_labels_affine(f, m); /* RAS -(0.5) x becomes LPS +0.5 */
  assert_close(m[0][0], 0.5, 1e-6);
  assert_close(m[0][3], -10.0, 1e-6);
  assert_close(m[1][3], -20.0, 1e-6);
  path_in(fx, "o.nii.gz", out);
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_labels_write(f, out, &err), LSM_OK);
  lsm_label_file *g = NULL;
  read_ok(out, &g);
  assert_memory_equal(lsm_labels_voxels(g)->data, values_4x3x2, sizeof values_4x3x2);
  lsm_labels_free(&g);
  lsm_labels_free(&f);
  /* refusals */
  write_nifti(p, &h, values_4x3x2, 10);
  expect_refused(p, "truncated", 0);
  nifti_1_header bad = h;
  bad.datatype = DT_COMPLEX64;
  bad.bitpix = 64;
  write_nifti(p, &bad, values_4x3x2, sizeof values_4x3x2);
  expect_refused(p, "not a label map", 0);
  bad = h;
  bad.dim[4] = 3;
  write_nifti(p, &bad, values_4x3x2, sizeof values_4x3x2);
  expect_refused(p, "a label volume is 3D", 0);
  bad = h;
  bad.scl_slope = 2.0f;
  write_nifti(p, &bad, values_4x3x2, sizeof values_4x3x2);
  expect_refused(p, "scales the stored values", 0);
  bad = h;
  bad.dim[1] = 30000;
  bad.dim[2] = 30000;
  bad.dim[3] = 30000;
  write_nifti(p, &bad, values_4x3x2, sizeof values_4x3x2);
  expect_refused(p, "", 0);
  path_in(fx, "junk.nii.gz", p);
  write_nrrd(p, "not gzip at all", NULL, 0);
  expect_refused(p, "cannot read", 0);
}

static void test_check_output(void **state) {
  tmp_fixture *fx = *state;
  char in[256], p[256];
  path_in(fx, "in.nrrd", in);
  write_nrrd(in, HEADER_4x3x2("ushort"), values_4x3x2, sizeof values_4x3x2);
  lsm_err err;
  lsm_err_clear(&err);
  path_in(fx, "out.png", p);
  assert_int_equal(lsm_labels_check_output(p, in, &err), LSM_ERR_USAGE);
  lsm_err_clear(&err);
  path_in(fx, "no/such/folder/out.nrrd", p);
  assert_int_equal(lsm_labels_check_output(p, in, &err), LSM_ERR_INPUT);
  assert_non_null(strstr(err.msg, "no such folder"));
  lsm_err_clear(&err);
  assert_int_equal(lsm_labels_check_output(in, in, &err), LSM_ERR_INPUT);
  assert_non_null(strstr(err.msg, "is the input file"));
  lsm_err_clear(&err);
  path_in(fx, "out.nii", p);
  assert_int_equal(lsm_labels_check_output(p, in, &err), LSM_OK);
  assert_int_equal(lsm_labels_format_of("A.SEG.NRRD"), LSM_LABELS_NRRD);
  assert_int_equal(lsm_labels_format_of("a.nii.GZ"), LSM_LABELS_NIFTI);
  assert_int_equal(lsm_labels_format_of("a.gz"), LSM_LABELS_UNKNOWN);
}

/* A temporary beside OUT left by a writer that was killed (its maker provably
 * ended: lsm_temp.h) is removed by the next write; one whose maker lives, or
 * of another machine, is left. */
static void test_stale_temporaries(void **state) {
  tmp_fixture *fx = *state;
  char mine[LSM_TEMP_TAG_MAX], dead[LSM_TEMP_TAG_MAX] = "";
  lsm_temp_tag(mine);
  if (!mine[0]) skip(); /* no /proc: nothing is ever shown to have ended */
  int fds[2];
  assert_int_equal(pipe(fds), 0);
  const pid_t child = fork();
  if (child == 0) {
    lsm_temp_tag(mine);
    _exit(write(fds[1], mine, sizeof mine) == (ssize_t)sizeof mine ? 0 : 1);
  }
  assert_true(child > 0);
  assert_int_equal(read(fds[0], dead, sizeof dead), (ssize_t)sizeof dead);
  close(fds[0]);
  close(fds[1]);
  waitpid(child, NULL, 0);
  const char *other = "1.2.0123456789abcdef";
  const char *tags[3] = {dead, mine, other};
  char in[256], out[256], p[300];
  for (int k = 0; k < 3; ++k) {
    snprintf(p, sizeof p, "%s/.out.nrrd.tmp-%s-Ab3dE9", fx->dir, tags[k]);
    write_nrrd(p, "x", NULL, 0);
  }
  path_in(fx, "in.nrrd", in);
  path_in(fx, "out.nrrd", out);
  write_nrrd(in, HEADER_4x3x2("ushort"), values_4x3x2, sizeof values_4x3x2);
  lsm_label_file *f = NULL;
  read_ok(in, &f);
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_labels_write(f, out, &err) != LSM_OK) fail_msg("%s", err.msg);
  lsm_labels_free(&f);
  for (int k = 0; k < 3; ++k) {
    snprintf(p, sizeof p, "%s/.out.nrrd.tmp-%s-Ab3dE9", fx->dir, tags[k]);
    assert_int_equal(access(p, F_OK) == 0, k > 0);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_nrrd_round_trip, setup, teardown),
      cmocka_unit_test_setup_teardown(test_nrrd_detached_gzip, setup, teardown),
      cmocka_unit_test_setup_teardown(test_float_labels, setup, teardown),
      cmocka_unit_test_setup_teardown(test_hostile_nrrd, setup, teardown),
      cmocka_unit_test_setup_teardown(test_nifti, setup, teardown),
      cmocka_unit_test_setup_teardown(test_check_output, setup, teardown),
      cmocka_unit_test_setup_teardown(test_stale_temporaries, setup, teardown),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
