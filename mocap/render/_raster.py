"""Compiled rasterizer kernels (private; see :mod:`mocap.render.rasterize` for the public API).

Buffers are flat (row-major, index ``row * width + col``):
- ``part_buf``  uint8: 0 background, else part index + 1;
- ``depth_buf`` float32: inverse depth 1/z in 1/metres (0 = nothing; larger is nearer);
- ``tri_buf``   int32: triangle index or -1 (optional: pass an empty array to skip);
- ``count_buf`` int32: how many triangles covered each pixel (optional, for tests).

Vertices are snapped to 1/SUBPIXEL of a pixel and edge functions are evaluated exactly in
integer arithmetic with the top-left fill rule, so triangles that share an edge neither leave
a crack nor both cover a pixel centre on it.
"""
from __future__ import annotations

import numpy as np
from numba.cpython.unsafe.numbers import trailing_zeros

from mocap._numba import jit

#: Fixed-point sub-pixel steps per pixel (4 bits, as GPUs use).
SUBPIXEL = 16
#: Largest |pixel coordinate| kept after projection (keeps integer edge functions in range).
_COORD_LIMIT = 1.0e6
#: Triangles whose pixel box is narrower than this are traversed pixel by pixel, not by runs.
_NARROW = 8


@jit
def _project_point(x, y, z, cam, i, xs, ys, iz):
    """Project the camera-space point (x, y, z) (metres) into slot ``i``: fixed-point pixel
    coordinates ``xs``, ``ys`` and ``iz`` = 1/z, or -1 (and 0, 0) nearer than ``cam[4]``."""
    if z < cam[4]:
        iz[i] = -1.0
        xs[i] = 0
        ys[i] = 0
        return
    inv = 1.0 / z
    u = min(max(cam[0] * x * inv + cam[2], -_COORD_LIMIT), _COORD_LIMIT)
    v = min(max(cam[1] * y * inv + cam[3], -_COORD_LIMIT), _COORD_LIMIT)
    iz[i] = inv
    xs[i] = np.int64(np.floor(u * SUBPIXEL + 0.5))
    ys[i] = np.int64(np.floor(v * SUBPIXEL + 0.5))


@jit
def _project_vertices(transforms, vertices, vertex_segment, cam, xs, ys, iz):
    """Transform segment-local vertices to the camera and project them (:func:`_project_point`)."""
    for i in range(vertices.shape[0]):
        s = vertex_segment[i]
        vx, vy, vz = vertices[i, 0], vertices[i, 1], vertices[i, 2]
        x = transforms[s, 0, 0] * vx + transforms[s, 0, 1] * vy + transforms[s, 0, 2] * vz + transforms[s, 0, 3]
        y = transforms[s, 1, 0] * vx + transforms[s, 1, 1] * vy + transforms[s, 1, 2] * vz + transforms[s, 1, 3]
        z = transforms[s, 2, 0] * vx + transforms[s, 2, 1] * vy + transforms[s, 2, 2] * vz + transforms[s, 2, 3]
        _project_point(x, y, z, cam, i, xs, ys, iz)


@jit
def _project_points(points, cam, xs, ys, iz):
    """As :func:`_project_vertices` for points already in camera coordinates."""
    for i in range(points.shape[0]):
        _project_point(points[i, 0], points[i, 1], points[i, 2], cam, i, xs, ys, iz)


@jit
def _floor_div(w, m, inv_m):
    """``(q, r)`` with ``w = q * m + r`` and ``0 <= r < m``, for integers w and m > 0 (exact);
    ``inv_m = 1.0 / m`` gives the estimate, integer arithmetic the correction."""
    q = np.int64(np.floor(w * inv_m))
    r = w - q * m
    while r < 0:
        q -= 1
        r += m
    while r >= m:
        q += 1
        r -= m
    return q, r


@jit
def _rasterize(xs, ys, iz, triangles, triangle_part, width, height, cull,
               part_buf, depth_buf, tri_buf, count_buf, bbox, fill=True):
    """Z-buffered rasterization of every triangle into the flat buffers, row span by row span.

    ``fill=False`` is a stage switch for profiles (``experiments.evaluation_profile``): every
    triangle is set up (culled, boxed, its edge functions and depth plane made, its rows cut)
    and ``bbox`` grows by its box as if it had been drawn (so it holds the drawn box), but no
    pixel is touched. Left out, the argument
    is a compile-time constant (Numba's omitted default), so the renders pay nothing for it.

    With ``cull`` only front-facing triangles (counter-clockwise from outside, i.e. negative
    signed area in y-down pixel coordinates) are drawn. ``bbox`` (int64[4]) receives the
    inclusive pixel box ``x0, y0, x1, y1`` touched (x0 > x1 when nothing was drawn).

    Each edge function is affine in the column: on a pixel row it is ``w - m * k`` at column
    ``px0 + k`` (``w``, ``m`` in 1/SUBPIXEL² pixel units), so the pixels where all three are
    >= 0 form one run. An edge with m > 0 (going down) ends the run at ``k = floor(w / m)``, one
    with m < 0 (going up) starts it at ``k = -floor(w / |m|)``; that quotient and its remainder
    are carried from row to row by an exact integer DDA (add the row step's quotient and
    remainder, carry one when the remainder reaches |m|), so exactly the pixels of the
    per-pixel test are drawn. A horizontal edge (m = 0) depends on the row only: it cuts the
    triangle's rows at set-up. When two edges go the same way, the triangle is drawn in two
    parts split at their shared vertex: above its row only the upper edge of the two can bind,
    from its row on only the lower one (on the vertex's own row both give the same bound),
    so each row tracks just one starting and one ending edge. Boxes narrower than
    :data:`_NARROW` pixels are cheaper to test pixel by pixel with the same integer edge
    functions, and are (unless triangle ids or coverage counts are asked for).

    Pixel writes are branch-free: the old part is loaded unconditionally and the depth test
    only selects what is stored. A write that loads the old part only when the test fails, or
    loads it before the depth store (LLVM then sinks the load into that case), compiles to a
    branch on the test, and from one pose to the next that branch is unpredictable: it cost
    a third of the render time at 160x120 (15.1 or 18.0 against 11.3 µs over 64 varied poses;
    a benchmark that repeats one pose hides it, as the branch predictor learns the pose).

    A pixel's inverse depth is its row's start plus ``dzdx`` times its column in the box, one
    multiply-add with no chain from pixel to pixel: an accumulated ``zz += dzdx`` made each
    pixel wait for the last one's addition (the run and narrow loops 5-15% slower, 160x120 to
    640x480; the stored float32 depths were the same on 256 varied poses at the three sizes).
    """
    S = SUBPIXEL
    half = S // 2
    want_tri = tri_buf.size > 0
    want_count = count_buf.size > 0
    bx0, by0, bx1, by1 = width, height, -1, -1
    for t in range(triangles.shape[0]):
        i0, i1, i2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        if iz[i0] <= 0.0 or iz[i1] <= 0.0 or iz[i2] <= 0.0:
            continue
        x0, y0 = xs[i0], ys[i0]
        x1, y1 = xs[i1], ys[i1]
        x2, y2 = xs[i2], ys[i2]
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if area == 0:
            continue
        if area < 0:
            # front-facing: swap to the positive orientation the traversal expects
            i1, i2 = i2, i1
            x1, y1, x2, y2 = x2, y2, x1, y1
            area = -area
        elif cull:
            continue
        # pixel box of the triangle, clamped to the image
        minx = min(x0, min(x1, x2))
        maxx = max(x0, max(x1, x2))
        miny = min(y0, min(y1, y2))
        maxy = max(y0, max(y1, y2))
        px0 = max((minx - half + S - 1) // S, 0)
        px1 = min((maxx - half) // S, width - 1)
        py0 = max((miny - half + S - 1) // S, 0)
        py1 = min((maxy - half) // S, height - 1)
        if px0 > px1 or py0 > py1:
            continue
        sx = px0 * S + half
        sy = py0 * S + half
        # inverse depth is affine in screen space: iz = z0 + dzdx * dx + dzdy * dy
        s_area = S / float(area)
        z0, z1, z2 = iz[i0], iz[i1], iz[i2]
        dzdx = ((z1 - z0) * (y2 - y0) - (z2 - z0) * (y1 - y0)) * s_area
        dzdy = ((x1 - x0) * (z2 - z0) - (x2 - x0) * (z1 - z0)) * s_area
        # renumber the vertices cyclically (same triangle, same orientation) so that edge 0,
        # the one opposite vertex 0, is horizontal or the only one going its way (up or down)
        up01, up12, up20 = y1 < y0, y2 < y1, y0 < y2
        if y1 == y0 or (y2 != y1 and y0 != y2 and up12 == up20):
            x0, y0, x1, y1, x2, y2 = x2, y2, x0, y0, x1, y1        # edge 01 becomes edge 0
        elif y0 == y2 or (y2 != y1 and up01 == up12):
            x0, y0, x1, y1, x2, y2 = x1, y1, x2, y2, x0, y0        # edge 20 becomes edge 0
        # edge functions E_ab(p) = (xb-xa)(py-ya) - (yb-ya)(px-xa), >= 0 inside; edge i is the
        # one opposite vertex i; top-left rule: bias -1 on edges that are neither top nor left
        a01x, a01y = x1 - x0, y1 - y0
        a12x, a12y = x2 - x1, y2 - y1
        a20x, a20y = x0 - x2, y0 - y2
        b0 = 0 if (a12y < 0 or (a12y == 0 and a12x > 0)) else -1
        b1 = 0 if (a20y < 0 or (a20y == 0 and a20x > 0)) else -1
        b2 = 0 if (a01y < 0 or (a01y == 0 and a01x > 0)) else -1
        w0_row = a12x * (sy - y1) - a12y * (sx - x1) + b0
        w1_row = a20x * (sy - y2) - a20y * (sx - x2) + b1
        w2_row = a01x * (sy - y0) - a01y * (sx - x0) + b2
        # per pixel step to the right: E -= m; per row step down: E += d
        m0, m1, m2 = a12y * S, a20y * S, a01y * S
        d0, d1, d2 = a12x * S, a20x * S, a01x * S
        n = px1 - px0
        if m0 == 0:
            # horizontal edge 0 keeps rows j (from py0) with w0 + j * d0 >= 0
            if d0 > 0:
                j_first = max(-(w0_row // d0), np.int64(0))
                if j_first > py1 - py0:
                    continue
                py0 += j_first
                sy = py0 * S + half
                w0_row += j_first * d0
                w1_row += j_first * d1
                w2_row += j_first * d2
            else:
                py1 = min(py1, py0 + w0_row // -d0)
                if py1 < py0:
                    continue
        n_rows = py1 - py0 + 1
        z_row = z0 + (dzdx * (sx - xs[i0]) + dzdy * (sy - ys[i0])) / S
        part_id = np.uint8(triangle_part[t] + 1)
        if not fill:
            if n_rows > 0:
                bx0 = min(bx0, px0)
                by0 = min(by0, py0)
                bx1 = max(bx1, px1)
                by1 = max(by1, py1)
            continue
        drawn = False
        if n < _NARROW and not (want_tri or want_count) and py1 * width + px0 + _NARROW <= part_buf.size:
            # narrow box, tried as _NARROW lanes a row (issue 50 item 2; slower: research log):
            # the depth test of every lane, its wins as bits, then the parts
            for py in range(py0, py1 + 1):
                row = py * width + px0
                wins = np.uint64(0)
                for k in range(_NARROW):
                    idx = np.uint64(row + k)
                    w0 = w0_row - m0 * k
                    w1 = w1_row - m1 * k
                    w2 = w2_row - m2 * k
                    inside = ((w0 | w1 | w2) >= 0) & (k <= n)
                    zz = z_row + dzdx * k
                    old_z = depth_buf[idx]
                    win = inside & (zz > old_z)
                    depth_buf[idx] = np.float32(zz) if win else old_z
                    wins |= np.uint64(win) << np.uint64(k)
                    drawn |= inside
                for k in range(_NARROW):
                    idx = np.uint64(row + k)
                    old_part = part_buf[idx]
                    part_buf[idx] = part_id if (wins >> np.uint64(k)) & np.uint64(1) else old_part
                w0_row += d0
                w1_row += d1
                w2_row += d2
                z_row += dzdy
        elif n < _NARROW and not (want_tri or want_count):
            # narrow box: testing every pixel of the row is cheaper than finding the run's ends
            for py in range(py0, py1 + 1):
                w0, w1, w2 = w0_row, w1_row, w2_row
                row = py * width + px0
                for k in range(n + 1):
                    idx = np.uint64(row + k)
                    zz = z_row + dzdx * k
                    old_z = depth_buf[idx]
                    inside = (w0 | w1 | w2) >= 0
                    win = inside & (zz > old_z)
                    depth_buf[idx] = np.float32(zz) if win else old_z
                    old_part = part_buf[idx]        # after the depth store: see the docstring
                    part_buf[idx] = part_id if win else old_part
                    drawn |= inside
                    w0 -= m0
                    w1 -= m1
                    w2 -= m2
                w0_row += d0
                w1_row += d1
                w2_row += d2
                z_row += dzdy
        else:
            # the edge starting the runs (lo, m < 0) and the one ending them (hi, m > 0) on rows
            # before j_split, and the edge (``next``) that takes over one of those roles from there
            if m0 == 0:
                j_split = n_rows
                if m1 < 0:
                    w_lo, m_lo, d_lo, w_hi, m_hi, d_hi = w1_row, m1, d1, w2_row, m2, d2
                else:
                    w_lo, m_lo, d_lo, w_hi, m_hi, d_hi = w2_row, m2, d2, w1_row, m1, d1
                w_next, m_next, d_next = w0_row, np.int64(1), d0
            else:
                # edges 1 and 2 meet at vertex 0: rows whose centre is above it are the first part
                j_split = min(max((y0 - sy + S - 1) // S, np.int64(0)), n_rows)
                if m0 < 0:          # edge 0 starts the runs; edge 1 (upper) then 2 (lower) end them
                    w_lo, m_lo, d_lo, w_hi, m_hi, d_hi = w0_row, m0, d0, w1_row, m1, d1
                    w_next, m_next, d_next = w2_row, m2, d2
                else:               # edge 0 ends the runs; edge 2 (upper) then 1 (lower) start them
                    w_lo, m_lo, d_lo, w_hi, m_hi, d_hi = w2_row, m2, d2, w0_row, m0, d0
                    w_next, m_next, d_next = w1_row, m1, d1
            # run ends by DDA: q = floor(w / |m|), r = w - q * |m| in [0, |m|)
            m_lo = -m_lo
            inv_lo, inv_hi = 1.0 / m_lo, 1.0 / m_hi
            q_lo, r_lo = _floor_div(w_lo, m_lo, inv_lo)
            dq_lo, dr_lo = _floor_div(d_lo, m_lo, inv_lo)
            q_hi, r_hi = _floor_div(w_hi, m_hi, inv_hi)
            dq_hi, dr_hi = _floor_div(d_hi, m_hi, inv_hi)
            j_from = np.int64(0)
            j_to = j_split
            row = py0 * width + px0
            for part in range(2):
                if part == 1:
                    if j_split >= n_rows:
                        break
                    # the next edge takes over from row j_split
                    mm = abs(m_next)
                    inv = 1.0 / mm
                    q, r = _floor_div(w_next + j_split * d_next, mm, inv)
                    dq, dr = _floor_div(d_next, mm, inv)
                    if m_next < 0:
                        q_lo, r_lo, dq_lo, dr_lo, m_lo = q, r, dq, dr, mm
                    else:
                        q_hi, r_hi, dq_hi, dr_hi, m_hi = q, r, dq, dr, mm
                    j_from, j_to = j_split, n_rows
                for j in range(j_from, j_to):
                    lo = max(-q_lo, np.int64(0))
                    hi = min(q_hi, n)
                    drawn |= lo <= hi       # (an empty run costs no branch: its loops do nothing)
                    if want_tri or want_count:
                        for k in range(lo, hi + 1):
                            idx = row + k
                            old_z = depth_buf[idx]
                            zz = z_row + dzdx * k
                            win = zz > old_z
                            depth_buf[idx] = np.float32(zz) if win else old_z
                            old_part = part_buf[idx]
                            part_buf[idx] = part_id if win else old_part
                            if want_tri:
                                old_tri = tri_buf[idx]
                                tri_buf[idx] = t if win else old_tri
                            if want_count:
                                count_buf[idx] += 1
                    else:
                        for k in range(lo, hi + 1):
                            idx = np.uint64(row + k)     # unsigned: no negative-index wrap-around
                            old_z = depth_buf[idx]
                            zz = z_row + dzdx * k
                            win = zz > old_z
                            depth_buf[idx] = np.float32(zz) if win else old_z
                            old_part = part_buf[idx]
                            part_buf[idx] = part_id if win else old_part
                    r_lo += dr_lo
                    carry = np.int64(r_lo >= m_lo)
                    q_lo += dq_lo + carry
                    r_lo -= m_lo & -carry
                    r_hi += dr_hi
                    carry = np.int64(r_hi >= m_hi)
                    q_hi += dq_hi + carry
                    r_hi -= m_hi & -carry
                    row += width
                    z_row += dzdy
        if drawn:
            bx0 = min(bx0, px0)
            by0 = min(by0, py0)
            bx1 = max(bx1, px1)
            by1 = max(by1, py1)
    bbox[0], bbox[1], bbox[2], bbox[3] = bx0, by0, bx1, by1


@jit
def _edge_scan(part_buf, depth_buf, width, height, bbox, min_gap, distance, mark_buf, clear):
    """Find the occluding-edge pixels of a render by scanning neighbour transitions.

    A model pixel is an occluding-edge pixel when one of its 4-neighbours inside the image is
    background, or belongs to another part and is farther by more than ``min_gap`` metres (the
    nearer side of a depth step is marked; creases between touching parts have no such step).
    Only pairs of differing neighbours do work, so interiors cost one comparison a pixel.

    Marks the pixels in the flat bool ``mark_buf`` and returns ``(sum of distance over them,
    their count)``; ``distance`` may be empty (then the sum is 0). With ``clear`` the part,
    depth and mark buffers are reset row by row as soon as no later pair needs them.
    """
    if bbox[0] > bbox[2]:
        return 0.0, 0
    xa, xb = max(bbox[0] - 1, 0), min(bbox[2] + 1, width - 1)
    ya, yb = max(bbox[1] - 1, 0), min(bbox[3] + 1, height - 1)
    # 8 pixels at a time: per word, the bytes that differ from their right / lower neighbour
    # say exactly which pairs need work; a word with none is skipped
    use_words = width % 8 == 0
    words = part_buf[: part_buf.size - part_buf.size % 8].view(np.uint64)
    row_words = width // 8
    have_distance = distance.size > 0
    total = 0.0
    n = 0
    for y in range(ya, yb + 1):
        row = y * width
        has_below = y < yb
        if use_words:
            for k in range((row + xa) // 8, (row + xb) // 8 + 1):
                x0 = k * 8 - row
                w = words[np.uint64(k)]
                right = w >> np.uint64(8)
                if x0 + 8 < width:
                    right |= words[np.uint64(k + 1)] << np.uint64(56)
                d_right = w ^ right
                d_below = w ^ words[np.uint64(k + row_words)] if has_below else np.uint64(0)
                if (d_right | d_below) == 0:
                    continue
                # the top bit of each byte that differs; then visit only those bytes, lowest
                # first (the order of a byte-by-byte loop). Bytes outside xa..xb never differ:
                # they and their neighbours lie outside the box, where nothing was drawn.
                r_bits = _nonzero_bytes(d_right)
                b_bits = _nonzero_bytes(d_below)
                pending = r_bits | b_bits
                while pending != 0:
                    top = trailing_zeros(pending)
                    pending &= pending - np.uint64(1)
                    bit = np.uint64(1) << top
                    r_diff = (r_bits & bit) != 0
                    b_diff = (b_bits & bit) != 0
                    i = np.int64(top) >> 3
                    a = row + x0 + i
                    pa = part_buf[np.uint64(a)]
                    if r_diff and x0 + i < xb:
                        j = _nearer_side(pa, part_buf[np.uint64(a + 1)], depth_buf[np.uint64(a)],
                                         depth_buf[np.uint64(a + 1)], a, a + 1, min_gap)
                        if j >= 0 and not mark_buf[np.uint64(j)]:
                            mark_buf[np.uint64(j)] = True
                            n += 1
                            if have_distance:
                                total += distance[np.uint64(j)]
                    if b_diff:
                        j = _nearer_side(pa, part_buf[np.uint64(a + width)], depth_buf[np.uint64(a)],
                                         depth_buf[np.uint64(a + width)], a, a + width, min_gap)
                        if j >= 0 and not mark_buf[np.uint64(j)]:
                            mark_buf[np.uint64(j)] = True
                            n += 1
                            if have_distance:
                                total += distance[np.uint64(j)]
        else:
            t, c = _scan_pixels(part_buf, depth_buf, width, row, xa, xb, xb, has_below, min_gap, distance,
                                mark_buf)
            total += t
            n += c
        if clear:
            _clear_row(part_buf, depth_buf, mark_buf, row, xa, xb)
    return total, n


#: The top bit of each byte of a 64-bit word.
_BYTE_TOPS = np.uint64(0x8080808080808080)
_LOW_SEVEN = np.uint64(0x7F7F7F7F7F7F7F7F)


@jit
def _nonzero_bytes(word):
    """The top bit of every byte of the uint64 ``word`` that is not 0 (others 0)."""
    return (((word & _LOW_SEVEN) + _LOW_SEVEN) | word) & _BYTE_TOPS


@jit
def _scan_pixels(part_buf, depth_buf, width, row, x_from, x_to, x_last, has_below, min_gap, distance, mark_buf):
    """Visit the right and lower neighbour pairs of pixels ``x_from..x_to`` of one row."""
    have_distance = distance.size > 0
    total = 0.0
    n = 0
    for x in range(x_from, x_to + 1):
        a = row + x
        pa = part_buf[a]
        for k in range(2):
            if k == 0:
                if x >= x_last:
                    continue
                b = a + 1
            else:
                if not has_below:
                    continue
                b = a + width
            pb = part_buf[b]
            if pa == pb:
                continue
            j = _nearer_side(pa, pb, depth_buf[a], depth_buf[b], a, b, min_gap)
            if j >= 0 and not mark_buf[j]:
                mark_buf[j] = True
                n += 1
                if have_distance:
                    total += distance[j]
    return total, n


@jit
def _nearer_side(pa, pb, za, zb, a, b, min_gap):
    """Which of two neighbouring pixels of different parts is an occluding-edge pixel: the model
    one next to background, else the nearer one when the depth step exceeds ``min_gap``
    (``za``, ``zb`` are inverse depths); -1 for none."""
    if pa == 0:
        return b
    if pb == 0:
        return a
    gap = min_gap * za * zb
    if za - zb > gap:
        return a
    if zb - za > gap:
        return b
    return -1


@jit
def _clear_row(part_buf, depth_buf, mark_buf, row, xa, xb):
    # slice fills compile to memset-like vector stores (an element loop with signed indices
    # does not: Numba's negative-index wrap-around keeps it scalar, ~10x slower)
    part_buf[row + xa: row + xb + 1] = 0
    depth_buf[row + xa: row + xb + 1] = 0.0
    mark_buf[row + xa: row + xb + 1] = False


@jit
def _clear(part_buf, depth_buf, width, bbox):
    """Reset the buffers inside ``bbox`` (the only place a render wrote)."""
    for py in range(bbox[1], bbox[3] + 1):
        row = py * width
        part_buf[row + bbox[0]: row + bbox[2] + 1] = 0
        depth_buf[row + bbox[0]: row + bbox[2] + 1] = 0.0
