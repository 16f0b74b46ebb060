"""Radiance .hdr (RGBE) reading and writing in numpy, for the environment-map tools.

Decoding follows Greg Ward's RGBE as Mitsuba 3, Bruce Walter's rgbe.c and Rust's `image`
crate read it: a texel (r, g, b, e) is (r, g, b) * 2^(e - 136), and (.., .., .., 0) is
black. (Radiance itself adds half a mantissa step, (r + 0.5) * 2^(e - 136); the maps we
ship are meant to be read without it, as Mitsuba reads them for the references.)

Encoding rounds each channel to the nearest mantissa step of the texel's shared exponent
(the exponent raised by one where the largest channel would round to 256), so that a value
that is representable (such as 1, 0.5, 1024, 3 * 2^-4) is written exactly. Scanlines are
written with the "new" run-length encoding (runs of equal bytes per channel, literal
chunks otherwise), which every reader of the format accepts for widths 8..32767; other
widths are written flat. Row 0 is the top of the image (-Y H +X W).
"""
import numpy as np

HEADER = b"#?RADIANCE\n"


def encode_rgbe(img):
    """float HxWx3 (finite, >= 0) -> uint8 HxWx4."""
    img = np.asarray(img, dtype=np.float64)
    if img.ndim != 3 or img.shape[2] != 3:
        raise ValueError("expected an HxWx3 image")
    if not np.all(np.isfinite(img)) or np.any(img < 0):
        raise ValueError("RGBE holds finite values >= 0 only")
    v = img.max(axis=2)
    _, e = np.frexp(v)                        # v = m 2^e, m in [0.5, 1)
    e = e.astype(np.int64)
    q = np.rint(img * np.ldexp(1.0, 8 - e)[:, :, None])
    over = q.max(axis=2) > 255
    e = np.where(over, e + 1, e)
    q = np.rint(img * np.ldexp(1.0, 8 - e)[:, :, None])
    tiny = (v < 1e-38) | (e + 128 < 1)
    if np.any(e + 128 > 255):
        raise ValueError("value too large for RGBE")
    out = np.zeros(img.shape[:2] + (4,), dtype=np.uint8)
    out[:, :, :3] = np.clip(q, 0, 255).astype(np.uint8)
    out[:, :, 3] = np.clip(e + 128, 0, 255).astype(np.uint8)
    out[tiny] = 0
    return out


def decode_rgbe(rgbe):
    """uint8 HxWx4 -> float64 HxWx3, (r, g, b) 2^(e - 136); e = 0 is black."""
    rgbe = np.asarray(rgbe)
    e = rgbe[:, :, 3].astype(np.int64)
    f = np.where(e == 0, 0.0, np.ldexp(1.0, e - 136))
    return rgbe[:, :, :3].astype(np.float64) * f[:, :, None]


def _rle_channel(row):
    """New-style RLE of one channel of a scanline: runs (count 128 + n, value) of 3..127
    equal bytes, literals (count n <= 128, n bytes) otherwise."""
    out = bytearray()
    n = len(row)
    i = 0
    lit = []

    def flush():
        while lit:
            chunk = lit[:128]
            del lit[:128]
            out.append(len(chunk))
            out.extend(chunk)
    while i < n:
        j = i
        while j < n and j - i < 127 and row[j] == row[i]:
            j += 1
        if j - i >= 3:
            flush()
            out.append(128 + (j - i))
            out.append(int(row[i]))
            i = j
        else:
            lit.append(int(row[i]))
            i += 1
    flush()
    return bytes(out)


def write_hdr(path, img, comment=None):
    """Writes float HxWx3 as a Radiance .hdr (RLE scanlines where the width allows)."""
    rgbe = encode_rgbe(img)
    h, w, _ = rgbe.shape
    head = bytearray(HEADER)
    if comment:
        for line in comment.splitlines():
            head += b"# " + line.encode("ascii") + b"\n"
    head += b"FORMAT=32-bit_rle_rgbe\n\n"
    head += b"-Y %d +X %d\n" % (h, w)
    body = bytearray()
    for y in range(h):
        row = rgbe[y]
        if 8 <= w <= 0x7FFF:
            body += bytes([2, 2, w >> 8, w & 0xFF])
            for c in range(4):
                body += _rle_channel(row[:, c])
        else:
            body += row.tobytes()
    with open(path, "wb") as fh:
        fh.write(bytes(head) + bytes(body))
    return decode_rgbe(rgbe)


def read_hdr(path):
    """A Radiance .hdr (-Y H +X W; flat, old-RLE-free or new-RLE scanlines) -> float64
    HxWx3, row 0 = the top."""
    with open(path, "rb") as fh:
        data = fh.read()
    if not (data.startswith(b"#?RADIANCE") or data.startswith(b"#?RGBE")):
        raise ValueError("%s: not a Radiance file" % path)
    pos = 0
    fmt = None
    while True:
        end = data.index(b"\n", pos)
        line = data[pos:end]
        pos = end + 1
        if not line:
            break
        if line.startswith(b"FORMAT="):
            fmt = line[7:].strip()
    if fmt not in (None, b"32-bit_rle_rgbe"):
        raise ValueError("%s: unsupported format %r" % (path, fmt))
    end = data.index(b"\n", pos)
    res = data[pos:end].split()
    pos = end + 1
    if len(res) != 4 or res[0] != b"-Y" or res[2] != b"+X":
        raise ValueError("%s: unsupported orientation %r" % (path, res))
    h, w = int(res[1]), int(res[3])
    out = np.zeros((h, w, 4), dtype=np.uint8)
    for y in range(h):
        if 8 <= w <= 0x7FFF and data[pos] == 2 and data[pos + 1] == 2 and data[pos + 2] < 128:
            if (data[pos + 2] << 8) | data[pos + 3] != w:
                raise ValueError("%s: scanline width mismatch" % path)
            pos += 4
            for c in range(4):
                x = 0
                while x < w:
                    n = data[pos]
                    pos += 1
                    if n > 128:
                        out[y, x:x + n - 128, c] = data[pos]
                        pos += 1
                        x += n - 128
                    else:
                        out[y, x:x + n, c] = np.frombuffer(data, np.uint8, n, pos)
                        pos += n
                        x += n
        else:
            out[y] = np.frombuffer(data, np.uint8, w * 4, pos).reshape(w, 4)
            pos += w * 4
    return decode_rgbe(out)
