/* A dependency-free PNG writer for 8-bit RGBA images (zlib "stored" blocks, no compression).
 * Enough for screenshots; header-only, C99. */
#ifndef NIMBUS_PNG_WRITE_H
#define NIMBUS_PNG_WRITE_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static inline uint32_t png_crc_update(uint32_t crc, const uint8_t *p, size_t n) {
    size_t i;
    int k;
    for (i = 0; i < n; i++) {
        crc ^= p[i];
        for (k = 0; k < 8; k++) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return crc;
}

static inline void png_put32(uint8_t *p, uint32_t v) {
    p[0] = (uint8_t)(v >> 24); p[1] = (uint8_t)(v >> 16); p[2] = (uint8_t)(v >> 8); p[3] = (uint8_t)v;
}

static inline int png_chunk(FILE *f, const char *type, const uint8_t *data, uint32_t len) {
    uint8_t head[8], tail[4];
    uint32_t crc;
    png_put32(head, len);
    memcpy(head + 4, type, 4);
    crc = png_crc_update(0xFFFFFFFFu, head + 4, 4);
    crc = png_crc_update(crc, data, len) ^ 0xFFFFFFFFu;
    png_put32(tail, crc);
    return fwrite(head, 1, 8, f) == 8 && (len == 0 || fwrite(data, 1, len, f) == len) && fwrite(tail, 1, 4, f) == 4;
}

/* Writes rows of width*4 bytes from the top. Returns 0 on success, -1 on failure. */
static inline int png_write_rgba8(const char *path, const uint8_t *rgba, uint32_t w, uint32_t h) {
    static const uint8_t sig[8] = {137, 80, 78, 71, 13, 10, 26, 10};
    size_t raw_len = (size_t)h * (1 + (size_t)w * 4), blocks = raw_len / 65535 + 1;
    size_t z_len = 2 + raw_len + blocks * 5 + 4, pos = 0, done = 0, y;
    uint8_t ihdr[13], *raw, *z;
    uint32_t a = 1, b = 0;
    FILE *f;
    int ok;
    raw = (uint8_t *)malloc(raw_len);
    z = (uint8_t *)malloc(z_len);
    if (!raw || !z) { free(raw); free(z); return -1; }
    for (y = 0; y < h; y++) {
        raw[y * (1 + (size_t)w * 4)] = 0; /* filter: none */
        memcpy(raw + y * (1 + (size_t)w * 4) + 1, rgba + y * (size_t)w * 4, (size_t)w * 4);
    }
    z[pos++] = 0x78; z[pos++] = 0x01;
    while (done < raw_len) {
        size_t n = raw_len - done > 65535 ? 65535 : raw_len - done;
        z[pos++] = (uint8_t)(done + n == raw_len);
        z[pos++] = (uint8_t)n; z[pos++] = (uint8_t)(n >> 8);
        z[pos++] = (uint8_t)~n; z[pos++] = (uint8_t)(~n >> 8);
        memcpy(z + pos, raw + done, n);
        pos += n; done += n;
    }
    for (y = 0; y < raw_len; y++) { a = (a + raw[y]) % 65521u; b = (b + a) % 65521u; }
    png_put32(z + pos, (b << 16) | a);
    pos += 4;
    png_put32(ihdr, w); png_put32(ihdr + 4, h);
    ihdr[8] = 8; ihdr[9] = 6; ihdr[10] = 0; ihdr[11] = 0; ihdr[12] = 0;
    f = fopen(path, "wb");
    ok = f && fwrite(sig, 1, 8, f) == 8 && png_chunk(f, "IHDR", ihdr, 13) &&
         png_chunk(f, "IDAT", z, (uint32_t)pos) && png_chunk(f, "IEND", NULL, 0);
    if (f && fclose(f) != 0) ok = 0;
    free(raw); free(z);
    return ok ? 0 : -1;
}

#endif
