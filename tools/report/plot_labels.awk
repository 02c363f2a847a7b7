# plot_labels.awk - the axis ranges and point labels of one report_plot
# (tools/report/lib.sh), as gnuplot commands on stdout.
#
# Input: report_plot's series list, one series a line, tab-separated: the
# data file (lines "X Y \"LABEL\"", blank lines between pieces), its colour,
# dash, point shape and title. Variables: xlog, ylog ("log" or empty), floor
# (where zero errors are drawn on a log axis, or empty), pw, ph: the plot
# area in pixels (report_plot fixes the margins).
#
# Ranges: the data's, padded (more on the right, where labels go first); a
# linear error axis from 0.
#
# Labels: each in its series' colour, at the first of a list of places
# around its point (right, left, above right, below right, above left, below
# left, then two and three lines up or down) where its box covers the least
# of what is already there: the boxes of the labels placed before, every
# point's marker, the lines between points (sampled every few pixels) and
# the space outside the plot area. Boxes are estimated from the character
# count (CHAR_W x CHAR_H pixels a character: sans 11 on pngcairo).
BEGIN {
    FS = "\t"
    CHAR_W = 7.5; CHAR_H = 15; MARK = 9; LINE_STEP = 4
    # candidate places: offset in characters (gnuplot's "offset char"), alignment
    nc = split("1 0 L;-1 0 R;0.6 1 L;0.6 -1 L;-0.6 1 R;-0.6 -1 R;1 2 L;1 -2 L;-1 2 R;-1 -2 R;1 3 L;1 -3 L;-1 3 R;-1 -3 R;0 4 L;0 -4 L", cand, ";")
    for (k = 1; k <= nc; k++) {
        split(cand[k], f, " ")
        cdx[k] = f[1]; cdy[k] = f[2]; cal[k] = f[3]
    }
}
function tx(v) { return xlog == "log" ? log(v) : v }
function ty(v) { return ylog == "log" ? log(v) : v }
function overlap(ax0, ay0, ax1, ay1, bx0, by0, bx1, by1,   w, h) {
    w = (ax1 < bx1 ? ax1 : bx1) - (ax0 > bx0 ? ax0 : bx0)
    h = (ay1 < by1 ? ay1 : by1) - (ay0 > by0 ? ay0 : by0)
    return w > 0 && h > 0 ? w * h : 0
}
function outside(x0, y0, x1, y1,   inside) {
    inside = overlap(x0, y0, x1, y1, 0, 0, pw, ph)
    return (x1 - x0) * (y1 - y0) - inside
}
{
    ns++
    colour[ns] = $2
    file = $1
    prev = 0
    while ((getline line < file) > 0) {
        if (line ~ /^[ \t]*$/) { prev = 0; continue }
        np++
        px[np] = substr(line, 1, index(line, " ") - 1)
        rest = substr(line, index(line, " ") + 1)
        py[np] = substr(rest, 1, index(rest, " ") - 1)
        text = substr(rest, index(rest, " ") + 1)
        gsub(/^"|"$/, "", text)
        ptext[np] = text
        pser[np] = ns
        pprev[np] = prev # the point this one is joined to (0: none)
        prev = np
    }
    close(file)
}
END {
    if (np == 0) exit
    xlo = xhi = tx(px[1]); ylo = yhi = ty(py[1])
    for (i = 2; i <= np; i++) {
        if (tx(px[i]) < xlo) xlo = tx(px[i]); if (tx(px[i]) > xhi) xhi = tx(px[i])
        if (ty(py[i]) < ylo) ylo = ty(py[i]); if (ty(py[i]) > yhi) yhi = ty(py[i])
    }
    dx = xhi - xlo; if (dx <= 0) dx = xlog == "log" ? log(10) : (xhi != 0 ? xhi : 1)
    xa = xlo - 0.06 * dx; xb = xhi + 0.16 * dx
    if (ylog == "log") {
        dy = yhi - ylo; if (dy <= 0) dy = log(10)
        ya = ylo - 0.06 * dy; yb = yhi + 0.08 * dy
    } else {
        ya = 0; yb = yhi > 0 ? 1.08 * yhi : 1
    }
    printf "set xrange [%.6g:%.6g]\n", xlog == "log" ? exp(xa) : xa, xlog == "log" ? exp(xb) : xb
    printf "set yrange [%.6g:%.6g]\n", ylog == "log" ? exp(ya) : ya, ylog == "log" ? exp(yb) : yb
    # pixels
    for (i = 1; i <= np; i++) {
        X[i] = (tx(px[i]) - xa) / (xb - xa) * pw
        Y[i] = (ty(py[i]) - ya) / (yb - ya) * ph
    }
    # obstacles: markers, then samples along the lines
    no = 0
    for (i = 1; i <= np; i++) {
        no++; ox0[no] = X[i] - MARK / 2; oy0[no] = Y[i] - MARK / 2; ox1[no] = X[i] + MARK / 2; oy1[no] = Y[i] + MARK / 2
        ow[no] = 1
        j = pprev[i]
        if (!j) continue
        len = sqrt((X[i] - X[j]) ^ 2 + (Y[i] - Y[j]) ^ 2)
        for (s = LINE_STEP; s < len - MARK / 2; s += LINE_STEP) {
            t = s / len
            no++
            ox0[no] = X[j] + t * (X[i] - X[j]) - 1; ox1[no] = ox0[no] + 2
            oy0[no] = Y[j] + t * (Y[i] - Y[j]) - 1; oy1[no] = oy0[no] + 2
            ow[no] = 0.5
        }
    }
    nl = 0
    for (i = 1; i <= np; i++) {
        if (ptext[i] == "") continue
        w = length(ptext[i]) * CHAR_W + 2
        best = 0; bestc = -1
        for (k = 1; k <= nc; k++) {
            ax = X[i] + cdx[k] * CHAR_W
            ay = Y[i] + cdy[k] * CHAR_H
            x0 = cal[k] == "L" ? ax : ax - w; x1 = x0 + w
            y0 = ay - CHAR_H / 2; y1 = ay + CHAR_H / 2
            c = 4 * outside(x0, y0, x1, y1) + 0.02 * k * CHAR_H
            for (l = 1; l <= nl; l++) c += 4 * overlap(x0, y0, x1, y1, lx0[l], ly0[l], lx1[l], ly1[l])
            for (o = 1; o <= no; o++) c += ow[o] * overlap(x0, y0, x1, y1, ox0[o], oy0[o], ox1[o], oy1[o])
            if (bestc < 0 || c < bestc) { bestc = c; best = k; bx0 = x0; by0 = y0; bx1 = x1; by1 = y1 }
        }
        nl++; lx0[nl] = bx0; ly0[nl] = by0; lx1[nl] = bx1; ly1[nl] = by1
        printf "set label %d \"%s\" at first %s, first %s %s offset char %g,%g textcolor rgb '%s' front\n",
            nl, ptext[i], px[i], py[i], cal[best] == "L" ? "left" : "right", cdx[best], cdy[best], colour[pser[i]]
    }
}
