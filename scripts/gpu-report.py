#!/usr/bin/env python3
"""Helpers of scripts/gpu-run.sh (Python's standard library alone: the GPU machine has nothing else
of ours).

    gpu-report.py add-spot SCENE.json OUT.json
        OUT.json: SCENE.json with a spot light aimed at its first mesh, paths made absolute;
        prints "octree PATH" for the scene's first scan.
    gpu-report.py path OCTREE OUT.json SECONDS
        OUT.json: a camera path for `nestlight render --path`: an orbit around the scan's bounds
        that closes in on its centre (streaming under the default budgets as the view changes).
    gpu-report.py report WORK OUT [--quick 0|1] [--threads N] [--deadline S]
        Reads what the run left in WORK (steps.jsonl, res/*.json, logs/*.log) and writes
        OUT/report.json and OUT/report.md: every figure beside its paper's anchor.
"""
import glob
import json
import math
import os
import re
import sys

# The figures the project's targets are set against (docs/GPU.md says where each comes from).
ANCHORS = {
    "render": "Schütz et al. 2021 (compute rasterisation): about 50 billion points/s brute force on an RTX 3090",
    "vpl": "Preiner: 8.7 ms a frame at 1024 VPLs with 64x64 ISMs on a GTX 980; the project's target "
           "10 ms at 1920x1080 with 1024 VPLs on a 100M-point streamed scan",
    "pbgi": "Sabbadin et al. 2019: X-PBGI up to 10x faster than Classic (512x512, 32x32 micro-buffers)",
    "ibl": "Kronander et al. 2015: 25-26 frames/s (38-40 ms) with SMC on a GTX 770 (resolution not given)",
    "gi": "time to reach 10% relative error of the path-traced reference (reference on every core)",
}
POINTS_ANCHOR = 50e9


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def fmt(v, digits=2):
    if v is None:
        return "-"
    if isinstance(v, float):
        if math.isnan(v):
            return "-"
        return ("%%.%df" % digits) % v
    return str(v)


def human(n):
    if n is None:
        return "-"
    for unit, scale in (("G", 1e9), ("M", 1e6), ("k", 1e3)):
        if abs(n) >= scale:
            return "%.2f %s" % (n / scale, unit)
    return "%.0f" % n


# --- add-spot -------------------------------------------------------------------------------------

def add_spot(scene_path, out_path):
    scene = load(scene_path)
    if scene is None:
        sys.exit("gpu-report: cannot read %s" % scene_path)
    base = os.path.dirname(os.path.abspath(scene_path))

    def absolute(p):
        return p if os.path.isabs(p) else os.path.normpath(os.path.join(base, p))

    for o in scene.get("octrees", []):
        if "path" in o:
            o["path"] = absolute(o["path"])
    for m in scene.get("meshes", []):
        if "path" in m:
            m["path"] = absolute(m["path"])
    env = scene.get("environment")
    if isinstance(env, dict) and "path" in env:
        env["path"] = absolute(env["path"])
    # Aim at the first mesh's translation (a 4x4 row-major matrix or a "translate" entry), else at
    # the camera's target.
    target = None
    if scene.get("meshes"):
        t = scene["meshes"][0].get("transform")
        if isinstance(t, list) and len(t) == 16:
            target = [t[3], t[7], t[11]]
        elif isinstance(t, list) and len(t) == 4 and all(isinstance(r, list) for r in t):
            target = [t[0][3], t[1][3], t[2][3]]
        elif isinstance(t, dict) and "translate" in t:
            target = list(t["translate"])
    if target is None:
        target = list(scene.get("camera", {}).get("target", [0, 0, 0]))
    position = [target[0], target[1], target[2] + 4.0]
    scene.setdefault("lights", []).append({
        "type": "spot", "position": position, "direction": [0, 0, -1], "intensity": 200,
        "inner_angle": 20, "outer_angle": 30})
    os.makedirs(os.path.dirname(os.path.abspath(out_path)), exist_ok=True)
    with open(out_path, "w") as f:
        json.dump(scene, f, indent=1)
    octrees = scene.get("octrees", [])
    if octrees:
        print("octree " + octrees[0]["path"])
    print("spot at %s aimed down at %s" % (position, target))


# --- path -----------------------------------------------------------------------------------------

def camera_path(octree, out_path, seconds):
    meta = load(os.path.join(octree, "metadata.json"))
    if meta is None:
        sys.exit("gpu-report: cannot read %s/metadata.json" % octree)
    lo, hi = meta["bounds"]["min"], meta["bounds"]["max"]
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    radius = max(hi[0] - lo[0], hi[1] - lo[1]) / 2 or 1.0
    keys = []
    steps = 12
    for i in range(steps + 1):
        f = i / steps
        angle = 2 * math.pi * f
        d = radius * (1.6 - 1.3 * f)  # from the whole scan to a close view of its centre
        eye = [centre[0] + d * math.cos(angle), centre[1] + d * math.sin(angle), centre[2] + 0.5 * d + 1.0]
        keys.append({"time": seconds * f, "eye": eye, "target": centre})
    with open(out_path, "w") as f:
        json.dump({"fps": 30, "fov": 60, "keyframes": keys}, f, indent=1)


def stream_path_summary(csv_path):
    import csv
    try:
        rows = list(csv.DictReader(open(csv_path)))
    except OSError:
        return None
    if not rows:
        return None

    def col(name):
        return sorted(float(r[name]) for r in rows if r.get(name) not in (None, ""))

    def pct(v, q):
        return v[min(len(v) - 1, int(q * len(v)))] if v else None
    out = {"frames": len(rows), "complete_frames": sum(1 for r in rows if r.get("complete") in ("1", "true"))}
    for name in ("ms_draw", "ms_update", "ms_upload", "ms_cut"):
        v = col(name)
        out[name] = {"median": pct(v, 0.5), "p95": pct(v, 0.95), "max": v[-1] if v else None}
    for name in ("cut_points", "draw_points", "resident_bytes"):
        v = col(name)
        out[name + "_max"] = v[-1] if v else None
    for name in ("uploads", "upload_bytes", "evictions", "cancelled", "bytes_read"):
        v = col(name)
        out[name + "_total"] = sum(v) if v else None
    return out


# --- report ---------------------------------------------------------------------------------------

TEST_LINE = re.compile(r"^\[\s*(OK|FAILED|SKIPPED|RUN)\s*\] (\S+?)(?: \((\d+) ms\))?$")
GOLDEN_LINE = re.compile(r"^golden (\S+): (\d+) of (\d+) pixels differ by more than ([0-9.]+) \(([0-9.]+)%\), "
                         r"max channel error ([0-9.]+)")


def gl_suites():
    """The GL test suites of the run, in the order of scripts/gpu-suites.txt."""
    names = []
    with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "gpu-suites.txt")) as f:
        for line in f:
            fields = line.split()
            if fields and not fields[0].startswith("#"):
                names.append(fields[0])
    return names


def parse_tests(log_path):
    """Per-test results from gtest's console output (a suite killed at its limit still reports the
    tests it finished; the one it was running is 'unfinished')."""
    tests, goldens, running, output = {}, [], None, []
    try:
        lines = open(log_path, errors="replace").read().splitlines()
    except OSError:
        return None, []
    for line in lines:
        m = TEST_LINE.match(line.strip())
        if m:
            what, name, ms = m.group(1), m.group(2), m.group(3)
            if what == "RUN":
                running, output = name, []
                tests.setdefault(name, {"status": "unfinished", "ms": None})
            elif "." in name and not name.endswith(",") and not (ms is None and name != running and name in tests):
                # (gtest's closing list repeats failed tests without their time: not a result)
                tests[name] = {"status": {"OK": "passed", "FAILED": "failed", "SKIPPED": "skipped"}[what],
                               "ms": int(ms) if ms else None}
                if what == "FAILED" and name == running:
                    # What the test said before failing: the assertion and its values.
                    first = next((i for i, l in enumerate(output) if "Failure" in l), 0)
                    tests[name]["message"] = [l[:240] for l in output[first:] if l.strip()][:10]
                running = None if running == name else running
            continue
        if running:
            output.append(line)
        g = GOLDEN_LINE.match(line.strip())
        if g:
            goldens.append({"golden": g.group(1), "differing": int(g.group(2)), "pixels": int(g.group(3)),
                            "tolerance": float(g.group(4)), "percent": float(g.group(5)),
                            "max_channel": float(g.group(6))})
    return tests, goldens


def report(work, out, quick, threads, deadline):
    steps = []
    try:
        for line in open(os.path.join(work, "steps.jsonl")):
            if line.strip():
                steps.append(json.loads(line))
    except OSError:
        pass
    res = os.path.join(work, "res")
    r = {"quick": bool(quick), "cpu_threads": threads, "deadline_s": deadline, "steps": steps,
         "anchors": ANCHORS}
    md = []

    gl = load(os.path.join(res, "gl-info.json")) or {}
    r["context"] = {k: gl.get(k) for k in ("context", "vendor", "renderer", "version", "glsl_version", "software",
                                           "limits", "extensions")}
    programs = gl.get("programs", [])
    r["programs"] = programs
    r["programs_summary"] = gl.get("programs_summary")
    md.append("# Nestlight GPU run%s\n" % (" (--quick: tiny sizes, not figures)" if quick else ""))
    md.append("- device: %s" % gl.get("renderer", "unknown"))
    md.append("- GL: %s; GLSL %s; %s" % (gl.get("version", "?"), gl.get("glsl_version", "?"), gl.get("context", "?")))
    md.append("- CPU threads: %s" % threads)
    md.append("")
    md.append("## Steps\n")
    md.append("| step | status | seconds | limit |")
    md.append("|---|---|---|---|")
    for s in steps:
        md.append("| %s | %s | %s | %s |" % (s["name"], s["status"], s.get("seconds"), s.get("limit")))
    md.append("")

    md.append("## 1. Shader programs\n")
    summary = gl.get("programs_summary")
    if summary:
        md.append("%d linked, %d failed, %d need extensions the driver lacks (%.0f ms in all).\n" %
                  (summary["ok"], summary["failed"], summary["unsupported"], summary["ms"]))
    for p in programs:
        if p["status"] != "ok":
            md.append("- **%s** %s: %s\n\n```\n%s\n```" % (p["name"], p["defines"], p["status"], p["log"].strip()))
    warned = [p for p in programs if p["status"] == "ok" and p.get("log", "").strip()]
    if warned:
        md.append("\nDriver warnings on %d programs (details.tar.gz, res/gl-info.json): %s\n" %
                  (len(warned), ", ".join(sorted({p["name"] for p in warned}))))

    md.append("## 2. GL test suites\n")
    r["tests"] = {}
    md.append("| suite | passed | failed | skipped | unfinished |")
    md.append("|---|---|---|---|---|")
    all_goldens = []
    failures = []
    for suite in gl_suites():
        tests, goldens = parse_tests(os.path.join(work, "logs", "tests-%s.log" % suite))
        if tests is None:
            md.append("| %s | - | - | - | not run |" % suite)
            continue
        r["tests"][suite] = tests
        all_goldens += goldens
        count = {k: sum(1 for t in tests.values() if t["status"] == k)
                 for k in ("passed", "failed", "skipped", "unfinished")}
        failures += ["%s: %s" % (suite, n) for n, t in tests.items() if t["status"] in ("failed", "unfinished")]
        md.append("| %s | %d | %d | %d | %d |" % (suite, count["passed"], count["failed"], count["skipped"],
                                                  count["unfinished"]))
    r["goldens"] = all_goldens
    for f in failures:
        md.append("- %s" % f)
        suite, name = f.split(": ", 1)
        message = r["tests"].get(suite, {}).get(name, {}).get("message")
        if message:
            md.append("\n```\n%s\n```" % "\n".join(message))
    if all_goldens:
        md.append("\nGolden images (made on llvmpipe) against this device:\n")
        md.append("| golden | pixels differing | max channel error |")
        md.append("|---|---|---|")
        for g in all_goldens:
            md.append("| %s | %.3f%% (tolerance %.4f) | %.4f |" % (g["golden"], g["percent"], g["tolerance"],
                                                                 g["max_channel"]))
    md.append("")

    md.append("## 3. Point rendering\n")
    br = load(os.path.join(res, "bench-render.json"))
    r["render"] = br
    if br:
        md.append("%dx%d; %s. Anchor: %s.\n" % (br.get("width", 0), br.get("height", 0), br.get("octree", ""),
                                               ANCHORS["render"]))
        md.append("| path | median ms | points | points/s | of the anchor |")
        md.append("|---|---|---|---|---|")
        for name, p in br.get("paths", {}).items():
            if "skipped" in p:
                md.append("| %s | - | - | - | %s |" % (name, p["skipped"]))
                continue
            pps = p.get("points_per_second")
            md.append("| %s (%s) | %s | %s | %s | %s |" % (name, p.get("variant", ""), fmt(p.get("median_ms")),
                                                         human(p.get("points")), human(pps),
                                                         "%.1f%%" % (100 * pps / POINTS_ANCHOR) if pps else "-"))
    else:
        md.append("not measured (see the steps)")
    md.append("")

    md.append("## 4. Streaming\n")
    bs = load(os.path.join(res, "bench-stream.json"))
    r["stream"] = bs
    if bs:
        md.append("```\n%s\n```" % json.dumps({k: v for k, v in bs.items() if not isinstance(v, (list, dict))},
                                               indent=1))
        for k, v in bs.items():
            if isinstance(v, dict):
                md.append("- %s: %s" % (k, json.dumps(v)[:600]))
    else:
        md.append("not measured (see the steps)")
    sp = stream_path_summary(os.path.join(res, "stream-path.csv"))
    r["stream_path"] = sp
    if sp:
        md.append("\nA camera path rendered at the run's size under the default budgets (5M points, 512 MiB, "
                  "32 MiB uploaded a frame; `render --path --stats`): %d frames, %d with the cut complete.\n" %
                  (sp["frames"], sp["complete_frames"]))
        md.append("| per frame | median ms | p95 ms | max ms |")
        md.append("|---|---|---|---|")
        for name in ("ms_draw", "ms_update", "ms_upload", "ms_cut"):
            v = sp[name]
            md.append("| %s | %s | %s | %s |" % (name, fmt(v["median"]), fmt(v["p95"]), fmt(v["max"])))
        md.append("\nlargest cut %s points, drawn %s, resident %s MiB; %s uploads (%s MiB), %s evictions, %s loads "
                  "cancelled, %s MiB read" % (human(sp["cut_points_max"]), human(sp["draw_points_max"]),
                                              fmt((sp["resident_bytes_max"] or 0) / 2**20, 1), fmt(sp["uploads_total"], 0),
                                              fmt((sp["upload_bytes_total"] or 0) / 2**20, 1), fmt(sp["evictions_total"], 0),
                                              fmt(sp["cancelled_total"], 0), fmt((sp["bytes_read_total"] or 0) / 2**20, 1)))
    md.append("")

    md.append("## 5. GI frames\n")
    frames = {}
    def order(path):
        name = os.path.basename(path)
        for i, m in enumerate(("raster", "vpl", "pbgi", "ibl")):
            if name.startswith("frame-" + m):
                digits = re.findall(r"\d+", name)
                return (i, name.split("_")[1] if m == "pbgi" else "", int(digits[-1]) if digits else 0, name)
        return (9, "", 0, name)
    for path in sorted(glob.glob(os.path.join(res, "frame-*.json")), key=order):
        name = os.path.basename(path)[len("frame-"):-len(".json")]
        j = load(path)
        if j:
            frames[name] = j
    r["frames"] = frames
    if frames:
        md.append("`bench frame`: GPU time per pass, median of the runs; interactive frames are tone-mapped and not "
                  "read back.\n")
        md.append("| run | size | interactive frame ms | GPU total ms | still frame ms | passes (interactive, ms) |")
        md.append("|---|---|---|---|---|---|")
        for name, j in frames.items():
            i = j.get("interactive", {})
            s = j.get("still", {})
            passes = ", ".join("%s %.2f" % (k, v) for k, v in sorted(i.get("passes_ms", {}).items(),
                                                                       key=lambda kv: -kv[1])[:6])
            md.append("| %s | %dx%d | %s | %s | %s | %s |" % (name, j.get("width", 0), j.get("height", 0),
                                                            fmt(i.get("frame_ms")), fmt(i.get("gpu_total_ms")),
                                                            fmt(s.get("frame_ms")), passes))
        md.append("")
        md.append("- vpl: %s" % ANCHORS["vpl"])
        v = frames.get("vpl_1024", {}).get("interactive", {})
        if v.get("frame_ms") is not None:
            md.append("  - measured: %.2f ms a frame at 1024 VPLs (%s the 10 ms target)" %
                      (v["frame_ms"], "within" if v["frame_ms"] <= 10 else "%.1fx" % (v["frame_ms"] / 10)))
        md.append("- pbgi: %s" % ANCHORS["pbgi"])
        for mb in ("16", "32", "8"):
            c = frames.get("pbgi_classic_" + mb, {}).get("interactive", {}).get("gpu_total_ms")
            x = frames.get("pbgi_x_" + mb, {}).get("interactive", {}).get("gpu_total_ms")
            if c and x:
                md.append("  - %sx%s micro-buffers: Classic %.2f ms, X-PBGI %.2f ms: %.2fx" % (mb, mb, c, x, c / x))
                r.setdefault("pbgi_ratio", {})[mb] = c / x
        md.append("- ibl: %s" % ANCHORS["ibl"])
    else:
        md.append("not measured (see the steps)")
    md.append("")

    md.append("## 6. Speed against error\n")
    md.append("%s.\n" % ANCHORS["gi"])
    r["bench_gi"] = {}
    for scene in ("cornell", "object"):
        j = load(os.path.join(res, "bench-gi-%s" % scene, "bench_gi.json"))
        if not j:
            md.append("- %s: not measured" % scene)
            continue
        r["bench_gi"][scene] = j
        md.append("### %s (%sx%s, %s)\n" % (scene, j.get("width"), j.get("height"), j.get("mode")))
        ref = j.get("reference", {})
        md.append("reference: %s\n" % ", ".join("%s %s" % (k, fmt(v, 3)) for k, v in ref.items()
                                                if not isinstance(v, (dict, list))))
        md.append("| method | time to 10% | time to 10% (4x4 means) | time to 1% |")
        md.append("|---|---|---|---|")

        def t(key, name):
            v = (j.get(key) or {}).get(name) or {}
            return ("%s ms" % fmt(v.get("ms"))) if v.get("ms") is not None else v.get("how", "-")
        for name in (j.get("time_to_10_percent") or {}):
            md.append("| %s | %s | %s | %s |" % (name, t("time_to_10_percent", name), t("time_to_10_percent_box4", name),
                                                 t("time_to_1_percent", name)))
        md.append("\n| method | quality | median ms | relative L2 | of 4x4 means |")
        md.append("|---|---|---|---|---|")
        for row in j.get("rows", []):
            md.append("| %s%s | %s %s | %s | %s | %s |" % (row.get("method"), (" " + row["variant"]) if row.get("variant") else "",
                                                          row.get("quality"), row.get("quality_name", ""),
                                                          fmt(row.get("median_ms")), fmt(row.get("relative_l2"), 4),
                                                          fmt(row.get("relative_l2_box4"), 4)))
        md.append("")

    with open(os.path.join(out, "report.json"), "w") as f:
        json.dump(r, f, indent=1)
    with open(os.path.join(out, "report.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    print("gpu-report: %s/report.md, %s/report.json" % (out, out))


def main():
    if len(sys.argv) >= 4 and sys.argv[1] == "add-spot":
        add_spot(sys.argv[2], sys.argv[3])
    elif len(sys.argv) == 5 and sys.argv[1] == "path":
        camera_path(sys.argv[2], sys.argv[3], float(sys.argv[4]))
    elif len(sys.argv) >= 4 and sys.argv[1] == "report":
        opts = {"--quick": "0", "--threads": "0", "--deadline": "0"}
        rest = sys.argv[4:]
        for i in range(0, len(rest) - 1, 2):
            if rest[i] in opts:
                opts[rest[i]] = rest[i + 1]
        report(sys.argv[2], sys.argv[3], opts["--quick"] == "1", int(opts["--threads"]), int(opts["--deadline"]))
    else:
        print(__doc__.strip(), file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
