/* LD_PRELOAD shim for the cross-check: rs274 prints its canonical calls with
 * "%.4f" (and "%f"), 1e-4 of a unit, too coarse to compare moves to 1e-9. This
 * shim replaces those conversions in the format strings of fprintf/vfprintf
 * (rs274 is built with _FORTIFY_SOURCE, so the __*_chk entry points) by "%.17g",
 * which prints every double exactly enough to read it back bit for bit. It
 * changes only how numbers are printed; LinuxCNC's code is not linked. */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static const char* widen(const char* fmt, char* buf, size_t n) {
  size_t o = 0;
  const char* p = fmt;
  while (*p && o + 8 < n) {
    if (strncmp(p, "%.4f", 4) == 0) { memcpy(buf + o, "%.17g", 5); o += 5; p += 4; }
    else if (strncmp(p, "%f", 2) == 0) { memcpy(buf + o, "%.17g", 5); o += 5; p += 2; }
    else buf[o++] = *p++;
  }
  if (*p) return fmt; /* too long to rewrite: print as is */
  buf[o] = 0;
  return buf;
}

int __vfprintf_chk(FILE* f, int flag, const char* fmt, va_list ap) {
  char b[4096];
  (void)flag;
  return vfprintf(f, widen(fmt, b, sizeof b), ap);
}

int __fprintf_chk(FILE* f, int flag, const char* fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  int r = __vfprintf_chk(f, flag, fmt, ap);
  va_end(ap);
  return r;
}
