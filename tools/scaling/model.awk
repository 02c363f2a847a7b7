# model.awk - the scaling model of BENCHMARKS.md "Scaling past this machine".
# Reads the facts tools/scaling_model.sh measured ("KEY VALUE" lines) and prints
# the fitted constants, the predictions and the assumptions as markdown tables.
#
# Per mesh, for a 1920x1080 frame of primary rays (eyelight, no shadows):
#   T(N) = max(C(N), d, K(N), M(N)) + s + rel(N) + tail(N)
#   C(N) = (W (1 + kappa) + d) / N + (tiles / N) L(N)    render work + display work shared by
#                                                       N threads, each paying its tile fetches
#   d     thread 0's display stage per frame (it shows frame i-1, then joins frame i's tiles)
#   K(N) = tiles L(N)      the tile counter's line can be owned by one core at a time
#   M(N) = R B / BW(N)     DRAM traffic of the frame at the assumed sustained bandwidth
#   s     serial section; rel(N) = rel2 + h (N - 2): the frame barrier's release (condvar
#         broadcast, every woken thread takes the barrier mutex in turn)
#   tail(N) = (W / tiles) (N - 1) / N   the last tile's expected idle at the frame's end
# W = T1 - d1 - s1 (one core's render work a frame), kappa fitted so that the model
# gives the measured T2; efficiency E(N) = T(1) / (N T(N)).
function max(a, b) { return a > b ? a : b }
function min(a, b) { return a < b ? a : b }
function log2(x) { return log(x) / log(2) }
# mean cost of one fetch of the tile counter when its line last belonged to a random
# one of N cores: same CCX (measured here), another CCX of the socket, the other socket
function line_ns(n,   pccx, psock, pccd) {
    if (n <= 1) return 0
    pccx = min(CCX, n) / n
    psock = n > SOCK ? (n - SOCK) / n : 0
    pccd = 1 - pccx - psock
    return pccx * LCCX + pccd * LCCD + psock * LSOCK
}
function bw(n) { return (n > SOCK ? 2 : 1) * BWS * 1e9 }
# frame time at n cores for mesh m; sets BIND to the binding term's name
function frame_t(m, n, dmode, hh, tiles_div,   W, d, tl, c, k, mm, t, top) {
    W = w[m]
    d = disp[m]
    if (dmode == "tiles") { W = W + d; d = 0 }
    tl = TILES / tiles_div
    if (n == 1) return w[m] + disp[m] + ser[m]
    c = (W * (1 + kap[m]) + d) / n + tl / n * line_ns(n) * 1e-9
    k = tl * line_ns(n) * 1e-9
    mm = R * bpr[m] / bw(n)
    top = c; BIND = "work"
    if (d > top) { top = d; BIND = "display" }
    if (k > top) { top = k; BIND = "tile counter" }
    if (mm > top) { top = mm; BIND = "DRAM" }
    t = top + ser[m] + rel2[m] + hh * (n - 2) + (W / tl) * (n - 1) / n
    if (hh * (n - 2) + rel2[m] > 0.5 * top && BIND == "work") BIND = "work, barrier"
    return t
}
function eff(m, n, dmode, hh, tiles_div) { return (w[m] + disp[m] + ser[m]) / (n * frame_t(m, n, dmode, hh, tiles_div)) }
{ f[$1] = $2 }
END {
    CCX = f["assume.ccx_cores"]; SOCK = f["assume.socket_cores"]
    LCCD = f["assume.l_ccd_ns"]; LSOCK = f["assume.l_socket_ns"]; BWS = f["assume.bw_socket_gbs"]
    R = f["frame.rays"]; TILES = f["frame.tiles"]
    # the tile counter on this machine: extra CPU per tile when 2 threads share it
    LCCX = max(0, f["tiles.2.thread_ns"] - f["tiles.1.thread_ns"])
    # the barrier's release per extra thread: least squares over the oversubscribed empty frames
    sx = sy = sxx = sxy = k = 0
    hkey = f["fit.stat"] == "cpu" ? ".cpu_ms" : ".release_ms"
    for (n = 2; n <= 64; n *= 2) if (("empty." n hkey) in f) {
        x = n; y = f["empty." n hkey] * 1e-3
        sx += x; sy += y; sxx += x * x; sxy += x * y; k++
    }
    H = k > 1 ? (k * sxy - sx * sy) / (k * sxx - sx * sx) : 0
    if (H < 0) H = 0
    nm = split("bunny dragon ctbunny", ms, " ")
    for (i = 1; i <= nm; i++) {
        m = ms[i]
        F = f[m ".frames"]
        t1[m] = f[m ".1.median_s"] / F; t2[m] = f[m ".2.median_s"] / F
        disp[m] = f[m ".1.display_ms"] * 1e-3
        ser[m] = f[m ".2.serial_ms"] * 1e-3
        rel2[m] = f[m ".2.release_ms"] * 1e-3
        if (f["fit.stat"] == "cpu") rel2[m] = f["empty.2.release_min_ms"] * 1e-3
        if (f["fit.stat"] == "cpu")
            w[m] = f[m ".1.cpu_ms"] * 1e-3 - disp[m] - f[m ".1.serial_ms"] * 1e-3
        else
            w[m] = t1[m] - disp[m] - f[m ".1.serial_ms"] * 1e-3
        rate[m] = R / w[m]
        # bytes a ray from DRAM: LL read misses + write misses (write-allocate: read + write-back)
        bpr[m] = (f[m ".ll4.dlmr"] + 2 * f[m ".ll4.dlmw"]) * 64 / R
        bpr32[m] = (f[m ".ll32.dlmr"] + 2 * f[m ".ll32.dlmw"]) * 64 / R
        rd4[m] = f[m ".ll4.dlmr"] / R
        tris[m] = f[m ".triangles"]
        # kappa: what the measured 2-thread frame has beyond the model's other terms
        c2 = t2[m] - ser[m] - rel2[m] - (w[m] / TILES) / 2 - TILES / 2 * line_ns(2) * 1e-9
        if (f["fit.stat"] == "cpu")
            kap[m] = (f[m ".2.cpu_ms"] - f[m ".1.cpu_ms"]) * 1e-3 / w[m]
        else
            kap[m] = (2 * c2 - disp[m]) / w[m] - 1
        kraw[m] = kap[m]
        if (kap[m] < 0) kap[m] = 0 # within the noise: no super-linear predictions
    }
    # the 100 M-triangle model: the CT bunny's constants, traversal cost ~ log2(triangles),
    # LL read misses a ray extrapolated by the power law through the dragon and the CT bunny
    m = "m100"; ms[++nm] = m
    tris[m] = 1e8
    rate[m] = rate["ctbunny"] * log2(tris["ctbunny"]) / log2(tris[m])
    w[m] = R / rate[m]
    disp[m] = disp["ctbunny"]; ser[m] = ser["ctbunny"]; rel2[m] = rel2["ctbunny"]; kap[m] = kap["ctbunny"]
    ex = log(rd4["ctbunny"] / rd4["dragon"]) / log(tris["ctbunny"] / tris["dragon"])
    rd4[m] = rd4["ctbunny"] * (tris[m] / tris["ctbunny"]) ^ ex
    wr = f["ctbunny.ll4.dlmw"] / R
    bpr[m] = (rd4[m] + 2 * wr) * 64
    bpr32[m] = bpr[m]
    name["bunny"] = "bunny (69 k tris)"; name["dragon"] = "dragon (871 k)"
    name["ctbunny"] = "CT bunny (4.15 M)"; name["m100"] = "100 M model (extrapolated)"

    print "#### Fitted constants (this machine, 1920x1080, eyelight primary rays)"
    print ""
    print "| mesh | T1 ms | T2 ms | measured E(2) (wall) | W ms (render, 1 core) | Mrays/s a core | d: display ms | s: serial ms | rel2: release ms | kappa | LL misses a ray: reads (4 MB / 32 MB LL) | B: DRAM bytes a ray (4 MB / 32 MB LL) |"
    print "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    for (i = 1; i <= nm; i++) {
        m = ms[i]
        if (m == "m100")
            printf "| %s | - | - | - | %.1f | %.2f | %.2f | %.4f | %.4f | %.3f | %.3f (power law, exponent %.2f) | %.1f |\n", name[m], 1e3 * w[m], 1e-6 * rate[m], 1e3 * disp[m], 1e3 * ser[m], 1e3 * rel2[m], kap[m], rd4[m], ex, bpr[m]
        else
            printf "| %s | %.1f | %.1f | %.3f | %.1f | %.2f | %.2f | %.4f | %.4f | %s | %.3f / %.3f | %.1f / %.1f |\n", name[m], 1e3 * t1[m], 1e3 * t2[m], t1[m] / (2 * t2[m]), 1e3 * w[m], 1e-6 * rate[m], 1e3 * disp[m], 1e3 * ser[m], 1e3 * rel2[m], kraw[m] < 0 ? sprintf("0 (fit %.3f)", kraw[m]) : sprintf("%.3f", kap[m]), rd4[m], f[m ".ll32.dlmr"] / R, bpr[m], bpr32[m]
    }
    print ""
    printf "Machine-wide constants: tiles a frame %d (16-px tiles); tile counter, extra time a tile when 2 threads on this machine's 2 cores share it L_ccx = %.1f ns (build/tile-contention: %.2f thread ns a tile alone, %.2f side by side); barrier release per extra thread h = %.2f us (slope over the oversubscribed empty frames, 2..64 threads, of %s).\n", TILES, LCCX, f["tiles.1.thread_ns"], f["tiles.2.thread_ns"], 1e6 * H, f["fit.stat"] == "cpu" ? "the CPU time a frame" : "the release"
    print ""
    split("8 16 32 64 128", ns, " ")
    NSC = 4
    split("convert|tiles|tiles|tiles", dm, "|")
    split("1|1|0|0", hs, "|")
    split("1|1|1|4", td, "|")
    title[1] = "(a) as built: display `convert` on thread 0, condvar barrier (h measured), 16-px tiles"
    title[2] = "(b) the display work in the render threads (`convert-tiles`, as the DRM display does), the rest as built"
    title[3] = "(c) as (b), and a barrier whose release does not grow with threads (h = 0)"
    title[4] = "(d) as (c), and 32-px tiles (a quarter of the counter's fetches)"
    for (sc = 1; sc <= NSC; sc++) {
        print "#### Predicted efficiency E(N) = T(1) / (N T(N)): " title[sc]
        print ""
        print "| mesh | 2 (model) | 8 | 16 | 32 | 64 | 128 | frames/s at 64 | binding term at 64 / 128 |"
        print "|---|---:|---:|---:|---:|---:|---:|---:|---|"
        for (i = 1; i <= nm; i++) {
            m = ms[i]
            hh = hs[sc] == 1 ? H : 0
            printf "| %s | %.3f", name[m], eff(m, 2, dm[sc], hh, td[sc])
            for (j = 1; j <= 5; j++) printf " | **%.3f**", eff(m, ns[j], dm[sc], hh, td[sc])
            fps = 1 / frame_t(m, 64, dm[sc], hh, td[sc])
            b64 = BIND
            frame_t(m, 128, dm[sc], hh, td[sc])
            printf " | %.0f | %s / %s |\n", fps, b64, BIND
        }
        print ""
    }
    # against Manta's 92 % of linear at 64 CPUs
    print "#### Against Manta (92 % of linear at 64 CPUs)"
    print ""
    for (sc = 1; sc <= NSC; sc++) {
        lo = 1e9; hi = -1
        for (i = 1; i <= nm; i++) {
            e = eff(ms[i], 64, dm[sc], hs[sc] == 1 ? H : 0, td[sc])
            lo = min(lo, e); hi = max(hi, e)
        }
        verdict = "below Manta's on all"
        if (hi >= 0.92) verdict = "at or above Manta's on some"
        if (lo >= 0.92) verdict = "at or above Manta's on all"
        printf "- %s: E(64) = %.3f-%.3f over the four meshes (%s).\n", title[sc], lo, hi, verdict
    }
    print ""
    print "#### The terms at 64 and 128 cores, as built (ms a frame)"
    print ""
    print "| mesh | N | work C(N) | display d | tile counter floor K(N) | DRAM floor M(N) | serial s | release rel(N) | tail | L(N) ns | DRAM GB/s demanded at full speed (of assumed) |"
    print "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    for (i = 1; i <= nm; i++) {
        m = ms[i]
        for (j = 4; j <= 5; j++) {
            n = ns[j]
            c = (w[m] * (1 + kap[m]) + disp[m]) / n + TILES / n * line_ns(n) * 1e-9
            printf "| %s | %d | %.3f | %.2f | %.3f | %.3f | %.4f | %.3f | %.4f | %.0f | %.0f (%.0f) |\n", name[m], n, 1e3 * c, 1e3 * disp[m], 1e3 * TILES * line_ns(n) * 1e-9, 1e3 * R * bpr[m] / bw(n), 1e3 * ser[m], 1e3 * (rel2[m] + H * (n - 2)), 1e3 * (w[m] / TILES) * (n - 1) / n, line_ns(n), n * rate[m] * bpr[m] / 1e9 / (1 + kap[m]), bw(n) / 1e9
        }
    }
    print ""
}
