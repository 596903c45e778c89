/* A TIFF slice rewritten while it is read gives an error, not SIGBUS (issue
 * 54, item 8).  The rewrite is made deterministic: this program interposes
 * libc's read() and mmap() for libtiff, and the moment libtiff first touches
 * the watched file past its 8-byte header (by mapping it, or by a read: of
 * the directory, or of the pixels), the file is cut to that header, as
 * another program rewriting it would.  A mapped file then faults (SIGBUS)
 * when libtiff reads its directory; a file that is read gives a short read,
 * which must become an error naming it.
 * The read runs in a child process so that a signal is reported, not fatal
 * to the test run. */
#define _DEFAULT_SOURCE /* syscall() */
#include "lsm_test.h"

#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <tiffio.h>
#include <unistd.h>

#include "io/lsm_io.h"

/* The interposers' state: libc's signatures leave no room for a context. */
static struct {
  char path[128]; /* the watched file */
  dev_t dev;
  ino_t ino;
  off_t below; /* reads past the header cut the file only below this offset (0: any) */
  int armed, cut;
} watch;

static int watched(int fd) {
  struct stat sb;
  return watch.armed && !watch.cut && fd >= 0 && fstat(fd, &sb) == 0 && sb.st_dev == watch.dev &&
         sb.st_ino == watch.ino;
}

static void cut_to_header(void) {
  watch.cut = 1;
  if (truncate(watch.path, 8) != 0) _exit(4);
}

ssize_t read(int fd, void *buf, size_t n) {
  if (watched(fd)) {
    const off_t at = lseek(fd, 0, SEEK_CUR);
    if (at > 0 && (watch.below == 0 || at < watch.below)) cut_to_header();
  }
  return (ssize_t)syscall(SYS_read, fd, buf, n);
}

void *mmap(void *addr, size_t len, int prot, int flags, int fd, off_t off) {
  void *p = (void *)syscall(SYS_mmap, addr, len, prot, flags, fd, off);
  if (p != MAP_FAILED && watched(fd)) cut_to_header();
  return p;
}

/* A 256 x 256 uncompressed gray TIFF as libtiff writes it: pixels first,
 * the directory after them, past the first page of the file. */
static void write_slice(const char *path) {
  TIFF *tif = TIFFOpen(path, "w");
  assert_non_null(tif);
  TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, 256u);
  TIFFSetField(tif, TIFFTAG_IMAGELENGTH, 256u);
  TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, (uint16_t)8);
  TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, (uint16_t)1);
  TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, 16u);
  uint8_t row[256];
  for (uint32_t y = 0; y < 256; ++y) {
    const int dy = (int)y - 128;
    for (int x = 0; x < 256; ++x) row[x] = (x - 128) * (x - 128) + dy * dy < 6400 ? 255 : 0;
    assert_int_equal(TIFFWriteScanline(tif, row, y, 0), 1);
  }
  assert_int_equal(TIFFWriteDirectory(tif), 1);
  TIFFClose(tif);
}

/* How the file is read, and when it is cut. */
enum { HEADER, PIXELS_CUT_AT_DIRECTORY, PIXELS_CUT_AT_DATA, CASES };
static const char *const case_names[CASES] = {"its header", "its pixels, cut at the directory",
                                              "its pixels, cut in the pixel data"};

/* In a child: 0 when the read is refused with the file's name, 1 when it
 * succeeds, 2 when it fails otherwise, 3 when the file was never cut. */
static int read_while_cut(const char *path, int how) {
  struct stat sb;
  if (stat(path, &sb) != 0) return 2;
  if (how == PIXELS_CUT_AT_DATA) { /* libtiff's files hold the pixels below the directory */
    FILE *f = fopen(path, "rb");
    uint8_t head[8];
    if (!f || fread(head, 1, 8, f) != 8) return 2;
    fclose(f);
    watch.below = (off_t)head[4] | (off_t)head[5] << 8 | (off_t)head[6] << 16 | (off_t)head[7] << 24;
  }
  snprintf(watch.path, sizeof watch.path, "%s", path);
  watch.dev = sb.st_dev;
  watch.ino = sb.st_ino;
  watch.armed = 1;
  lsm_err err;
  lsm_err_clear(&err);
  lsm_status st;
  if (how == HEADER) {
    int w = 0, h = 0;
    st = lsm_tiff_read_header(path, 0, &w, &h, &err);
  } else {
    lsm_mask m;
    st = lsm_tiff_read_mask(path, NULL, &m, &err);
    if (st == LSM_OK) lsm_mask_free(&m);
  }
  watch.armed = 0;
  if (!watch.cut) return 3;
  if (st == LSM_OK) return 1;
  return st == LSM_ERR_INPUT && strncmp(err.msg, path, strlen(path)) == 0 ? 0 : 2;
}

static void test_rewritten_while_read(void **state) {
  (void)state;
  char dir[] = "/tmp/lsm_test_tiff_cut_XXXXXX";
  assert_non_null(mkdtemp(dir));
  char path[128];
  snprintf(path, sizeof path, "%s/slice.tif", dir);
  for (int how = 0; how < CASES; ++how) {
    write_slice(path);
    struct stat sb;
    assert_int_equal(stat(path, &sb), 0);
    assert_true(sb.st_size > 65536); /* the directory lies past the first page */
    fflush(NULL);
    const pid_t child = fork();
    assert_true(child >= 0);
    if (child == 0) { /* a fault kills the child, not cmocka's handler in it */
      signal(SIGBUS, SIG_DFL);
      signal(SIGSEGV, SIG_DFL);
      _exit(read_while_cut(path, how));
    }
    int status = 0;
    assert_int_equal(waitpid(child, &status, 0), child);
    if (WIFSIGNALED(status))
      fail_msg("reading %s (%s) while it was cut: killed by signal %d%s", path,
               case_names[how], WTERMSIG(status),
               WTERMSIG(status) == SIGBUS ? " (SIGBUS: the file was mapped)" : "");
    assert_true(WIFEXITED(status));
    switch (WEXITSTATUS(status)) {
    case 0: break;
    case 1: fail_msg("%s (%s) was read whole although it was cut", path, case_names[how]); break;
    case 3: fail_msg("%s (%s): libtiff never read past the header", path, case_names[how]); break;
    default:
      fail_msg("%s (%s): not refused as input naming the file (exit %d)", path, case_names[how],
               WEXITSTATUS(status));
    }
    unlink(path);
  }
  rmdir(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_rewritten_while_read),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
