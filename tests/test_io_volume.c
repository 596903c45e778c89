/* Tests of the io room's volume writers: NRRD (round trip, the fixed header,
 * errors), NIfTI-1 volume.nii (every header field at its offset, the 16-bit
 * size limits) and the gzip stream with a rewritable head behind
 * volume.nii.gz, which must inflate to volume.nii's bytes. */
#include "tests/lsm_test_io.h"

#include <sys/stat.h>
#include <zlib.h>

#include "io/lsm_io.h"

/* ---- NRRD ------------------------------------------------------------------------------- */

static uint32_t le32(const uint8_t *p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static int has_line(const char *header, const char *line) {
  size_t n = strlen(line);
  for (const char *p = header; (p = strstr(p, line)) != NULL; ++p)
    if ((p == header || p[-1] == '\n') && p[n] == '\n') return 1;
  return 0;
}

static void test_nrrd_roundtrip(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "vol.nrrd");
  enum { NX = 4, NY = 3, NZ = 3 };
  float vals[NZ][NX * NY];
  for (int z = 0; z < NZ; ++z)
    for (int k = 0; k < NX * NY; ++k) vals[z][k] = (float)(z * 100 + k) * 0.25f - 7.0f;
  vals[1][5] = 1e-30f;
  vals[2][0] = -0.0f;
  vals[2][11] = 3.4e38f;

  lsm_nrrd_writer *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, NX, NY, 0.5, 0.25, 1.0, -1.5, 0.0, 3.25, &w, &err), LSM_OK);
  assert_non_null(w);
  for (int z = 0; z < NZ; ++z) {
    assert_int_equal(lsm_nrrd_slices(w), (size_t)z);
    assert_int_equal(lsm_nrrd_write_slice(w, vals[z], &err), LSM_OK);
  }
  assert_int_equal(lsm_nrrd_slices(w), NZ);
  assert_int_equal(lsm_nrrd_finish(&w, 2.5, &err), LSM_OK);
  assert_null(w);

  size_t len = 0;
  uint8_t *data = read_bytes(path, &len);
  size_t header_len = 0;
  for (size_t k = 0; k + 1 < len && header_len == 0; ++k)
    if (data[k] == '\n' && data[k + 1] == '\n') header_len = k + 2;
  assert_true(header_len > 0);
  assert_int_equal(len, header_len + (size_t)NX * NY * NZ * 4);

  char *header = malloc(header_len + 1);
  assert_non_null(header);
  memcpy(header, data, header_len);
  header[header_len] = '\0';
  assert_true(strncmp(header, "NRRD0004\n", 9) == 0);
  assert_true(has_line(header, "type: float"));
  assert_true(has_line(header, "dimension: 3"));
  assert_true(has_line(header, "sizes: 4 3 3"));
  assert_true(has_line(header, "space dimension: 3"));
  assert_true(has_line(header, "space directions: (0.5,0,0) (0,0.25,0) (0,0,2.5)"));
  assert_true(has_line(header, "space origin: (-1.5,0,3.25)"));
  assert_true(has_line(header, "kinds: domain domain domain"));
  assert_true(has_line(header, "endian: little"));
  assert_true(has_line(header, "encoding: raw"));
  assert_null(strstr(header, "space:"));
  /* every line is a field, a comment or the final blank line */
  for (const char *p = header + 9; *p && p[0] != '\n'; p = strchr(p, '\n') + 1) {
    const char *colon = strstr(p, ": ");
    assert_true(p[0] == '#' || (colon && colon < strchr(p, '\n')));
  }
  free(header);

  for (int z = 0; z < NZ; ++z)
    for (int k = 0; k < NX * NY; ++k) {
      uint32_t want;
      memcpy(&want, &vals[z][k], sizeof want);
      uint32_t got = le32(data + header_len + 4 * ((size_t)z * NX * NY + (size_t)k));
      if (got != want) fail_msg("float %d,%d: got 0x%08x, want 0x%08x", z, k, got, want);
    }
  free(data);
}

static void test_nrrd_fixed_header(void **state) {
  /* the header length does not depend on the numbers in it */
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "one.nrrd");
  float slice[2] = {1.0f, 2.0f};
  size_t lengths[2];
  for (int pass = 0; pass < 2; ++pass) {
    lsm_nrrd_writer *w = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    double s = pass ? 0.1234567890123456789e-300 : 1.0;
    assert_int_equal(lsm_nrrd_open(path, 2, 1, s, s, s, -s, -s, -s, &w, &err), LSM_OK);
    for (int z = 0; z < (pass ? 12 : 1); ++z) assert_int_equal(lsm_nrrd_write_slice(w, slice, &err), LSM_OK);
    if (lsm_nrrd_finish(&w, pass ? -1.0 / 3.0 * -1e300 : 1.0, &err) != LSM_OK) fail_msg("%s", err.msg);
    size_t len;
    uint8_t *data = read_bytes(path, &len);
    lengths[pass] = len - (pass ? 12u : 1u) * 8u;
    if (pass) assert_true(has_line((const char *)data, "sizes: 2 1 12"));
    free(data);
  }
  assert_int_equal(lengths[0], lengths[1]);
}

static void test_nrrd_errors(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  lsm_nrrd_writer *w = NULL;
  lsm_err err;

  join(path, sizeof path, f->dir, "no/such/dir/v.nrrd");
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 4, 3, 1, 1, 1, 0, 0, 0, &w, &err), LSM_ERR_IO);
  assert_null(w);
  assert_msg_contains(err, path);

  join(path, sizeof path, f->dir, "v.nrrd");
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 0, 3, 1, 1, 1, 0, 0, 0, &w, &err), LSM_ERR_INPUT);
  assert_null(w);
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 4, 3, 1, NAN, 1, 0, 0, 0, &w, &err), LSM_ERR_INPUT);
  assert_null(w);

  /* finishing with no slices is refused */
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 4, 3, 1, 1, 1, 0, 0, 0, &w, &err), LSM_OK);
  assert_int_equal(lsm_nrrd_finish(&w, 1.0, &err), LSM_ERR_INPUT);
  assert_null(w);
  assert_msg_contains(err, path);

  /* abort frees everything (valgrind checks) */
  float slice[12] = {0};
  lsm_err_clear(&err);
  assert_int_equal(lsm_nrrd_open(path, 4, 3, 1, 1, 1, 0, 0, 0, &w, &err), LSM_OK);
  assert_int_equal(lsm_nrrd_write_slice(w, slice, &err), LSM_OK);
  lsm_nrrd_abort(&w);
  assert_null(w);
  lsm_nrrd_abort(&w); /* twice is harmless */

  struct stat sb;
  if (stat("/dev/full", &sb) == 0 && S_ISCHR(sb.st_mode)) {
    lsm_err_clear(&err);
    lsm_status st = lsm_nrrd_open("/dev/full", 4, 3, 1, 1, 1, 0, 0, 0, &w, &err);
    for (int z = 0; st == LSM_OK && z < 3; ++z) st = lsm_nrrd_write_slice(w, slice, &err);
    if (st == LSM_OK) st = lsm_nrrd_finish(&w, 1.0, &err);
    else lsm_nrrd_abort(&w);
    assert_int_equal(st, LSM_ERR_IO);
    assert_null(w);
    assert_msg_contains(err, "/dev/full");
  }
}

/* ---- NIfTI-1 (volume.nii) ------------------------------------------------------------ */

static int16_t le16s(const uint8_t *p) { return (int16_t)(uint16_t)(p[0] | (p[1] << 8)); }

static float le_f32(const uint8_t *p) {
  uint32_t u = le32(p);
  float v;
  memcpy(&v, &u, sizeof v);
  return v;
}

/* Writes volume.nii and volume.raw of three slices through the volume writer;
 * returns volume.nii's bytes (and *len). */
static uint8_t *write_nii(const char *dir, lsm_values values, size_t *len, uint8_t **raw,
                          size_t *raw_len) {
  enum { NX = 4, NY = 3, NZ = 3 };
  float vals[NZ][NX * NY];
  for (int z = 0; z < NZ; ++z)
    for (int k = 0; k < NX * NY; ++k) vals[z][k] = (float)(z * 100 + k) * 0.25f - 7.0f;
  vals[1][5] = 0.0f; /* phi = 0 counts as inside in a mask */
  lsm_volume_writer *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  if (lsm_volume_writer_open(dir, LSM_FORMAT_NII | LSM_FORMAT_RAW, values, NX, NY, 0.5, 0.25,
                             9.0, 1.5, 0.0, 3.25, &w, &err) != LSM_OK)
    fail_msg("%s", err.msg);
  for (int z = 0; z < NZ; ++z)
    assert_int_equal(lsm_volume_writer_write_slice(w, vals[z], 3.25 + 2.5 * z, &err), LSM_OK);
  if (lsm_volume_writer_finish(&w, 2.5, NZ, &err) != LSM_OK) fail_msg("%s", err.msg);
  char path[256];
  join(path, sizeof path, dir, "volume.raw");
  *raw = read_bytes(path, raw_len);
  join(path, sizeof path, dir, "volume.nii");
  return read_bytes(path, len);
}

/* Every field a reader needs, at its offset in the NIfTI-1 layout; the samples
 * after byte 352 are volume.raw's. */
static void test_nifti_header_fields(void **state) {
  tmp_fixture *f = *state;
  for (int pass = 0; pass < 2; ++pass) {
    const int mask = pass == 1;
    size_t len = 0, raw_len = 0;
    uint8_t *raw = NULL;
    uint8_t *h = write_nii(f->dir, mask ? LSM_VALUES_MASK : LSM_VALUES_SDF, &len, &raw, &raw_len);
    const size_t samples = 4 * 3 * 3, bytes = samples * (mask ? 1u : 4u);
    assert_int_equal(len, LSM_NIFTI_HEADER_BYTES + bytes);
    assert_int_equal(raw_len, bytes);
    assert_int_equal(le32(h + 0), 348);                /* sizeof_hdr: little endian */
    assert_int_equal(h[38], 'r');
    const int16_t dim[8] = {3, 4, 3, 3, 1, 1, 1, 1};
    for (int k = 0; k < 8; ++k) assert_int_equal(le16s(h + 40 + 2 * k), dim[k]);
    assert_int_equal(le16s(h + 70), mask ? 2 : 16);   /* DT_UINT8 / DT_FLOAT32 */
    assert_int_equal(le16s(h + 72), mask ? 8 : 32);
    const float pixdim[4] = {1.0f, 0.5f, 0.25f, 2.5f}; /* qfac, then the final z step */
    for (int k = 0; k < 4; ++k) assert_true(le_f32(h + 76 + 4 * k) == pixdim[k]);
    assert_true(le_f32(h + 108) == 352.0f);            /* vox_offset */
    assert_true(le_f32(h + 112) == 1.0f && le_f32(h + 116) == 0.0f); /* scl_slope, inter */
    assert_true(le_f32(h + 124) == (mask ? 255.0f : 0.0f) && le_f32(h + 128) == 0.0f);
    assert_int_equal(h[123], 0);                       /* xyzt_units: unknown */
    assert_int_equal(le16s(h + 252), 1);               /* qform_code */
    assert_int_equal(le16s(h + 254), 1);               /* sform_code */
    const float quat[6] = {0.0f, 0.0f, 1.0f, -1.5f, 0.0f, 3.25f}; /* b c d, offsets */
    for (int k = 0; k < 6; ++k) assert_true(le_f32(h + 256 + 4 * k) == quat[k]);
    assert_false(h[272 + 3] & 0x80);                   /* qoffset_y is +0, not -0 */
    const float srow[12] = {-0.5f, 0, 0, -1.5f, 0, -0.25f, 0, 0, 0, 0, 2.5f, 3.25f};
    for (int k = 0; k < 12; ++k)
      if (le_f32(h + 280 + 4 * k) != srow[k])
        fail_msg("srow element %d: %g, want %g", k, (double)le_f32(h + 280 + 4 * k),
                 (double)srow[k]);
    assert_memory_equal(h + 344, "n+1", 4);
    for (int k = 348; k < 352; ++k) assert_int_equal(h[k], 0); /* no extensions */
    assert_non_null(memchr(h + 148, '\0', 80));        /* descrip is terminated */
    assert_memory_equal(h + LSM_NIFTI_HEADER_BYTES, raw, bytes);
    if (mask) {
      assert_int_equal(h[LSM_NIFTI_HEADER_BYTES + 12 + 5], 255); /* phi = 0: inside */
      for (size_t k = 0; k < samples; ++k)
        assert_true(h[LSM_NIFTI_HEADER_BYTES + k] == 0 || h[LSM_NIFTI_HEADER_BYTES + k] == 255);
    }
    free(h);
    free(raw);
  }
}

/* NIfTI-1 sizes are 16-bit: wider slices are refused at open, a 32768th slice
 * when it comes; the header builder refuses them too. */
static void test_nifti_limits(void **state) {
  tmp_fixture *f = *state;
  lsm_volume_writer *w = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_volume_writer_open(f->dir, LSM_FORMAT_NII, LSM_VALUES_SDF,
                                          LSM_NIFTI_DIM_MAX + 1, 1, 1, 1, 1, 0, 0, 0, &w, &err),
                   LSM_ERR_LIMIT);
  assert_null(w);
  assert_msg_contains(err, "32767");
  lsm_err_clear(&err);
  assert_int_equal(lsm_volume_writer_open(f->dir, LSM_FORMAT_NII, LSM_VALUES_MASK, 1, 1, 1, 1,
                                          1, 0, 0, 0, &w, &err),
                   LSM_OK);
  const float one = -1.0f;
  lsm_status st = LSM_OK;
  for (int k = 0; st == LSM_OK && k < LSM_NIFTI_DIM_MAX; ++k)
    st = lsm_volume_writer_write_slice(w, &one, k, &err);
  assert_int_equal(st, LSM_OK);
  assert_int_equal(lsm_volume_writer_write_slice(w, &one, 1e6, &err), LSM_ERR_LIMIT);
  assert_msg_contains(err, "volume.nii");
  assert_int_equal(lsm_volume_writer_finish(&w, 1.0, LSM_NIFTI_DIM_MAX + 1, &err), LSM_ERR_IO);
  assert_null(w);

  unsigned char h[LSM_NIFTI_HEADER_BYTES];
  lsm_volume_info info = {2, 2, LSM_NIFTI_DIM_MAX, 1, 1, 1, 0, 0, 0, LSM_VALUES_SDF};
  assert_int_equal(lsm_nifti_header(h, sizeof h, &info), LSM_NIFTI_HEADER_BYTES);
  assert_int_equal(lsm_nifti_header(h, sizeof h - 1, &info), 0);
  info.nz = LSM_NIFTI_DIM_MAX + 1;
  assert_int_equal(lsm_nifti_header(h, sizeof h, &info), 0);
  info.nz = 1;
  info.ny = LSM_NIFTI_DIM_MAX + 1;
  assert_int_equal(lsm_nifti_header(h, sizeof h, &info), 0);

  unsigned formats = 0;
  lsm_err_clear(&err);
  assert_int_equal(lsm_format_list_parse("nii,nrrd", &formats, &err), LSM_OK);
  assert_int_equal(formats, LSM_FORMAT_NII | LSM_FORMAT_NRRD);
  assert_string_equal(lsm_format_name(LSM_FORMAT_NII), "nii");
  const char *names[8];
  assert_int_equal(lsm_volume_file_names(LSM_FORMAT_ALL, names, 8), 8);
  assert_int_equal(lsm_volume_file_names(LSM_FORMAT_NII, names, 8), 1);
  assert_string_equal(names[0], "volume.nii");
  lsm_err_clear(&err);
  assert_int_equal(lsm_format_list_parse("nifti", &formats, &err), LSM_ERR_USAGE);
  assert_msg_contains(err, "nii");
}

/* ---- gzip with a rewritable head (volume.nii.gz) ------------------------------------- */

/* Inflates a whole gzip file with zlib (any number of members); returns the
 * bytes (and *len), or NULL when zlib finds the stream broken. */
static uint8_t *gunzip_bytes(const uint8_t *gz, size_t gz_len, size_t *len) {
  size_t cap = 1 << 16, n = 0;
  uint8_t *out = malloc(cap);
  assert_non_null(out);
  z_stream z;
  memset(&z, 0, sizeof z);
  assert_int_equal(inflateInit2(&z, 16 + MAX_WBITS), Z_OK);
  z.next_in = (Bytef *)(uintptr_t)gz;
  z.avail_in = (uInt)gz_len;
  int r = Z_OK;
  while (r != Z_STREAM_END) {
    if (n == cap) {
      cap *= 2;
      out = realloc(out, cap);
      assert_non_null(out);
    }
    z.next_out = out + n;
    z.avail_out = (uInt)(cap - n);
    r = inflate(&z, Z_NO_FLUSH);
    n = cap - z.avail_out;
    if (r != Z_OK && r != Z_STREAM_END) break;
  }
  const int whole = r == Z_STREAM_END && z.avail_in == 0; /* one member, nothing after */
  inflateEnd(&z);
  if (!whole) {
    free(out);
    return NULL;
  }
  *len = n;
  return out;
}

/* The head written at open is replaced at finish; the file is one plain gzip
 * member that zlib inflates to the new head and the data, CRC and length
 * checked by zlib; the head lies uncompressed at LSM_GZIP_HEAD_OFFSET. */
static void test_gzip_rewritable_head(void **state) {
  tmp_fixture *f = *state;
  char path[256];
  join(path, sizeof path, f->dir, "x.gz");
  enum { HEAD = 352, DATA = 300000 };
  unsigned char head0[HEAD], head1[HEAD];
  uint8_t *data = malloc(DATA);
  assert_non_null(data);
  uint32_t seed = 12345u;
  for (int k = 0; k < HEAD; ++k) {
    head0[k] = (unsigned char)k;
    head1[k] = (unsigned char)(255 - k);
  }
  for (int k = 0; k < DATA; ++k) { /* half noise (incompressible), half runs */
    seed = seed * 1664525u + 1013904223u;
    data[k] = k < DATA / 2 ? (uint8_t)(seed >> 24) : (uint8_t)(k / 1000);
  }
  for (int level = 0; level <= 9; level += 9) {
    lsm_gzip_writer *g = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, head0, HEAD, level, &g, &err), LSM_OK);
    size_t at = 0, step = 1;
    while (at < DATA) { /* uneven pieces: 1, 3, 9, ... bytes */
      size_t piece = step < DATA - at ? step : DATA - at;
      assert_int_equal(lsm_gzip_writer_write(g, data + at, piece, &err), LSM_OK);
      at += piece;
      step *= 3;
    }
    assert_int_equal(lsm_gzip_writer_finish(&g, NULL, head1, &err), LSM_OK);
    assert_null(g);
    size_t gz_len = 0, len = 0;
    uint8_t *gz = read_bytes(path, &gz_len);
    assert_memory_equal(gz, "\x1f\x8b\x08", 3);
    assert_memory_equal(gz + LSM_GZIP_HEAD_OFFSET, head1, HEAD);
    uint8_t *plain = gunzip_bytes(gz, gz_len, &len);
    if (!plain) fail_msg("zlib cannot inflate the file written at level %d", level);
    assert_int_equal(len, HEAD + DATA);
    assert_memory_equal(plain, head1, HEAD);
    assert_memory_equal(plain + HEAD, data, DATA);
    assert_int_equal(le32(gz + gz_len - 4), HEAD + DATA); /* ISIZE */
    if (level == 9) assert_true(gz_len < HEAD + DATA * 3 / 4); /* the runs compress */
    free(gz);
    free(plain);
  }
  free(data);

  /* no head at all, no data: still a valid (empty) gzip file */
  lsm_gzip_writer *g = NULL;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, NULL, 0, 1, &g, &err), LSM_OK);
  assert_int_equal(lsm_gzip_writer_finish(&g, NULL, NULL, &err), LSM_OK);
  size_t gz_len = 0, len = 1;
  uint8_t *gz = read_bytes(path, &gz_len);
  uint8_t *plain = gunzip_bytes(gz, gz_len, &len);
  assert_non_null(plain);
  assert_int_equal(len, 0);
  free(gz);
  free(plain);

  /* a plain prefix before the member (volume.nrrd's header with encoding gzip), rewritten at
   * the end: the file is the new prefix, then a gzip member of the data alone */
  {
    const unsigned char pre0[] = "PROVISIONAL HEADER\n\n", pre1[] = "the final header..\n\n";
    const size_t pre = sizeof pre0 - 1;
    assert_int_equal(sizeof pre1 - 1, pre);
    const uint8_t bytes[5] = {1, 2, 3, 4, 5};
    assert_int_equal(lsm_gzip_writer_open(path, pre0, pre, NULL, 0, 1, &g, &err), LSM_OK);
    assert_int_equal(lsm_gzip_writer_write(g, bytes, sizeof bytes, &err), LSM_OK);
    assert_int_equal(lsm_gzip_writer_finish(&g, pre1, NULL, &err), LSM_OK);
    gz = read_bytes(path, &gz_len);
    assert_true(gz_len > pre);
    assert_memory_equal(gz, pre1, pre);
    plain = gunzip_bytes(gz + pre, gz_len - pre, &len);
    assert_non_null(plain);
    assert_int_equal(len, sizeof bytes);
    assert_memory_equal(plain, bytes, sizeof bytes);
    free(gz);
    free(plain);
    /* a prefix promised but not given at the end is an error */
    assert_int_equal(lsm_gzip_writer_open(path, pre0, pre, NULL, 0, 1, &g, &err), LSM_OK);
    lsm_err_clear(&err);
    assert_int_equal(lsm_gzip_writer_finish(&g, NULL, NULL, &err), LSM_ERR_INTERNAL);
    assert_null(g);
  }

  /* errors are values, with the file named */
  lsm_err_clear(&err);
  join(path, sizeof path, f->dir, "missing/x.gz");
  assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, head0, HEAD, 1, &g, &err), LSM_ERR_IO);
  assert_null(g);
  assert_msg_contains(err, "missing/x.gz");
  assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, head0, 70000, 1, &g, &err), LSM_ERR_INTERNAL);
  assert_int_equal(lsm_gzip_writer_open(path, NULL, 0, head0, HEAD, 10, &g, &err), LSM_ERR_INTERNAL);
  lsm_gzip_writer_abort(&g);
  lsm_gzip_writer_abort(NULL);
}

/* volume.nii.gz inflates to volume.nii's bytes, header included (slice count
 * and z step fixed at the end), for float and mask volumes. */
static void test_nifti_gz_is_nii(void **state) {
  tmp_fixture *f = *state;
  for (int mask = 0; mask < 2; ++mask) {
    lsm_volume_writer *w = NULL;
    lsm_err err;
    lsm_err_clear(&err);
    enum { NX = 37, NY = 29, NZ = 11 };
    float *phi = malloc(sizeof(float) * NX * NY);
    assert_non_null(phi);
    assert_int_equal(lsm_volume_writer_open(f->dir, LSM_FORMAT_NII | LSM_FORMAT_NII_GZ,
                                            mask ? LSM_VALUES_MASK : LSM_VALUES_SDF, NX, NY, 0.5,
                                            0.5, 7.0, 0.0, 0.0, 2.0, &w, &err),
                     LSM_OK);
    for (int z = 0; z < NZ; ++z) {
      for (int k = 0; k < NX * NY; ++k) phi[k] = (float)((k % NX) - 18) * 0.3f + (float)z;
      assert_int_equal(lsm_volume_writer_write_slice(w, phi, 2.0 + 1.5 * z, &err), LSM_OK);
    }
    free(phi);
    if (lsm_volume_writer_finish(&w, 1.5, NZ, &err) != LSM_OK) fail_msg("%s", err.msg);
    char path[256];
    size_t nii_len = 0, gz_len = 0, len = 0;
    join(path, sizeof path, f->dir, "volume.nii");
    uint8_t *nii = read_bytes(path, &nii_len);
    join(path, sizeof path, f->dir, "volume.nii.gz");
    uint8_t *gz = read_bytes(path, &gz_len);
    uint8_t *plain = gunzip_bytes(gz, gz_len, &len);
    assert_non_null(plain);
    assert_int_equal(nii_len, LSM_NIFTI_HEADER_BYTES + (size_t)NX * NY * NZ * (mask ? 1 : 4));
    assert_int_equal(len, nii_len);
    assert_memory_equal(plain, nii, nii_len);
    assert_int_equal(le16s(plain + 46), NZ);
    free(nii);
    free(gz);
    free(plain);
  }
  unsigned formats = 0;
  lsm_err err;
  lsm_err_clear(&err);
  assert_int_equal(lsm_format_list_parse("nii.gz,nii", &formats, &err), LSM_OK);
  assert_int_equal(formats, LSM_FORMAT_NII | LSM_FORMAT_NII_GZ);
  assert_string_equal(lsm_format_name(LSM_FORMAT_NII_GZ), "nii.gz");
  const char *names[8];
  assert_int_equal(lsm_volume_file_names(LSM_FORMAT_NII_GZ, names, 8), 1);
  assert_string_equal(names[0], "volume.nii.gz");
  /* the 16-bit limit names the file written */
  lsm_volume_writer *w = NULL;
  assert_int_equal(lsm_volume_writer_open(f->dir, LSM_FORMAT_NII_GZ, LSM_VALUES_SDF,
                                          LSM_NIFTI_DIM_MAX + 1, 1, 1, 1, 1, 0, 0, 0, &w, &err),
                   LSM_ERR_LIMIT);
  assert_msg_contains(err, "volume.nii.gz");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_nrrd_roundtrip, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nrrd_fixed_header, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nrrd_errors, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nifti_header_fields, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nifti_limits, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_gzip_rewritable_head, setup_tmp, teardown_tmp),
      cmocka_unit_test_setup_teardown(test_nifti_gz_is_nii, setup_tmp, teardown_tmp),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
