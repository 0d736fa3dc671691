/* Tracks frames through the C API and checks that misuse is refused, never a crash.
 *
 * usage: track_frames fx fy cx cy FRAME.pgm...
 * Prints one JSON line per frame: {"frame": i, "maxilla_from_mandible": [16 numbers] | null,
 * "tags": [maxilla, mandible]}; then "misuse: ok" once every misuse check passed. Each frame is
 * copied once into a buffer with padded rows (bytes_per_row > width), as camera buffers have,
 * and tracked in place from there. Exit status 0 only if everything passed. */
#include "jawtrack.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;

#define CHECK(cond, ...)                                  \
  do {                                                    \
    if (!(cond)) {                                        \
      fprintf(stderr, "FAILED %s:%d: ", __FILE__, __LINE__); \
      fprintf(stderr, __VA_ARGS__);                       \
      fprintf(stderr, "\n");                              \
      failures++;                                         \
    }                                                     \
  } while (0)

/* Reads a binary PGM (P5, maxval 255) into a buffer whose rows are `pad` bytes longer. */
static unsigned char *read_pgm(const char *path, uint32_t pad, uint32_t *w, uint32_t *h, uint32_t *stride) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  unsigned maxval;
  if (fscanf(f, "P5 %u %u %u", w, h, &maxval) != 3 || maxval != 255 || fgetc(f) == EOF) {
    fclose(f);
    return NULL;
  }
  *stride = *w + pad;
  unsigned char *buf = calloc((size_t)*stride * *h, 1);
  for (uint32_t y = 0; buf && y < *h; y++) {
    if (fread(buf + (size_t)y * *stride, 1, *w, f) != *w) {
      free(buf);
      buf = NULL;
    }
  }
  fclose(f);
  return buf;
}

static void expect_error(JtStatus got, JtStatus want, const char *what, const char *needle) {
  char message[512];
  size_t n = jt_last_error(message, sizeof message);
  CHECK(got == want, "%s: status %d, expected %d", what, (int)got, (int)want);
  CHECK(n > 0 && strstr(message, needle) != NULL, "%s: message '%s' lacks '%s'", what, message, needle);
}

int main(int argc, char **argv) {
  if (argc < 6) {
    fprintf(stderr, "usage: %s fx fy cx cy FRAME.pgm...\n", argv[0]);
    return 2;
  }
  JtIntrinsics k = {atof(argv[1]), atof(argv[2]), atof(argv[3]), atof(argv[4]), 0.0, 0.0};
  JtSettings settings = jt_settings_default();
  uint64_t tracker = 0;
  CHECK(jt_tracker_new(&settings, NULL, &tracker) == JT_STATUS_OK && tracker != 0, "jt_tracker_new");

  uint32_t w = 0, h = 0, stride = 0;
  unsigned char *frame = NULL;
  for (int i = 5; i < argc; i++) {
    free(frame);
    frame = read_pgm(argv[i], 64, &w, &h, &stride);
    if (!frame) {
      fprintf(stderr, "cannot read %s as a binary PGM\n", argv[i]);
      return 2;
    }
    JtFrameSummary s;
    JtStatus st = jt_track_luma(tracker, frame, (size_t)stride * h, w, h, stride, &k, (i - 5) / 30.0, 0.002, &s);
    CHECK(st == JT_STATUS_OK, "frame %d: status %d", i - 5, (int)st);
    printf("{\"frame\": %llu, \"maxilla_from_mandible\": ", (unsigned long long)s.frame);
    if (s.has_maxilla_from_mandible) {
      printf("[");
      for (int j = 0; j < 16; j++) printf("%s%.17g", j ? ", " : "", s.maxilla_from_mandible[j]);
      printf("]");
    } else {
      printf("null");
    }
    printf(", \"tags\": [%u, %u]}\n", s.maxilla.tag_count, s.mandible.tag_count);
  }

  /* Misuse: every call returns an error code and a message. */
  size_t len = (size_t)stride * h;
  expect_error(jt_track_luma(tracker, NULL, len, w, h, stride, &k, 0.0, 0.0, NULL), JT_STATUS_NULL_POINTER, "null frame", "luma");
  expect_error(jt_track_luma(tracker, frame, len, w, h, stride, NULL, 0.0, 0.0, NULL), JT_STATUS_NULL_POINTER, "null intrinsics", "intrinsics");
  expect_error(jt_track_luma(tracker, frame, len, w, h, w - 1, &k, 0.0, 0.0, NULL), JT_STATUS_INVALID_ARGUMENT, "stride < width", "bytes_per_row");
  expect_error(jt_track_luma(tracker, frame, len / 2, w, h, stride, &k, 0.0, 0.0, NULL), JT_STATUS_INVALID_ARGUMENT, "short buffer", "needs");
  expect_error(jt_track_luma(tracker, frame, len, 0, h, stride, &k, 0.0, 0.0, NULL), JT_STATUS_INVALID_ARGUMENT, "zero width", "empty");
  JtIntrinsics bad = k;
  bad.fx = -1.0;
  expect_error(jt_track_luma(tracker, frame, len, w, h, stride, &bad, 0.0, 0.0, NULL), JT_STATUS_INVALID_ARGUMENT, "negative focal length", "intrinsics");
  expect_error(jt_track_bgra(tracker, frame, len, w, h, stride, &k, 0.0, 0.0, NULL), JT_STATUS_INVALID_ARGUMENT, "BGRA rows too short", "bytes_per_row");
  expect_error(jt_track_luma(tracker, frame, len, w, h, stride, &k, 0.0, -0.002, NULL), JT_STATUS_INVALID_ARGUMENT, "negative exposure", "exposure");
  JtSettings wrong = settings;
  wrong.decimate = 2.5f;
  uint64_t other = 0;
  expect_error(jt_tracker_new(&wrong, NULL, &other), JT_STATUS_INVALID_ARGUMENT, "bad decimation", "decimation");
  JtSettings slow = settings;
  slow.readout_s = 0.5;
  expect_error(jt_tracker_new(&slow, NULL, &other), JT_STATUS_INVALID_ARGUMENT, "readout of half a second", "readout");
  expect_error(jt_tracker_new(NULL, "{\"version\": 9}", &other), JT_STATUS_INVALID_ARGUMENT, "bad marker file", "marker");
  expect_error(jt_tracker_new(NULL, NULL, NULL), JT_STATUS_NULL_POINTER, "null handle_out", "handle_out");
  CHECK(jt_tracker_free(tracker) == JT_STATUS_OK, "free");
  expect_error(jt_track_luma(tracker, frame, len, w, h, stride, &k, 0.0, 0.0, NULL), JT_STATUS_NO_SUCH_TRACKER, "freed handle", "no tracker");
  expect_error(jt_tracker_free(tracker), JT_STATUS_NO_SUCH_TRACKER, "double free", "no tracker");
  expect_error(jt_track_luma(987654321, frame, len, w, h, stride, &k, 0.0, 0.0, NULL), JT_STATUS_NO_SUCH_TRACKER, "made-up handle", "no tracker");
  char tiny[8];
  size_t full = jt_last_error(tiny, sizeof tiny);
  CHECK(full > sizeof tiny && strlen(tiny) == sizeof tiny - 1, "jt_last_error cuts to fit (%zu, '%s')", full, tiny);
  CHECK(jt_last_error(NULL, 0) == full, "jt_last_error(NULL, 0) gives the length");
  free(frame);

  if (failures == 0) printf("misuse: ok\n");
  return failures == 0 ? 0 : 1;
}
