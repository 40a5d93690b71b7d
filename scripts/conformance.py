#!/usr/bin/env python3
"""glTF conformance sweep: every .gltf / .glb under a folder rendered through visbuf and forward, baked, and the pack
rendered again; one Markdown table row per file (scripts/conformance.sh is the entry point).

A file passes when it renders, its image matches the forward path's at >= --min-psnr dB, it bakes and its pack
renders and matches forward too; or when visbuf refuses it with a clear error (exit code 1) AND the file is listed
in the folder's expectations (a line `refuse <relative path>  <regex of the message>` in --expect). Anything
else fails the sweep: a crash or signal, a timeout, an exit code other than 0/1, an image below the PSNR bar, an
unexpected refusal, or an expected refusal that now loads.
"""
import argparse
import concurrent.futures
import json
import os
import re
import subprocess
import sys
import tempfile

SIZE = "256x192"


def run(cmd, timeout):
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, errors="replace",
                           timeout=timeout)
        return p.returncode, p.stderr
    except subprocess.TimeoutExpired:
        return None, "timeout after %d s" % timeout


def first_error(stderr):
    for line in stderr.splitlines():
        if "error" in line:
            return line.strip()
    lines = [l for l in stderr.splitlines() if l.strip()]
    return lines[-1].strip() if lines else ""


def warnings_of(stderr):
    return [l.split("warning:", 1)[1].strip() for l in stderr.splitlines() if "warning:" in l]


def render(visbuf, scene, json_path, timeout):
    code, err = run([visbuf, "render", "--scene", scene, "--size", SIZE, "--reference", "--json", json_path, "-o", ""],
                    timeout)
    stats = None
    if code == 0:
        with open(json_path) as f:
            stats = json.load(f)
    return code, err, stats


def psnr_of(stats):
    return float(stats["reference"]["error"]["psnr"])


def sweep_one(args, rel, work):
    path = os.path.join(args.folder, rel)
    stem = re.sub(r"[^A-Za-z0-9_.-]", "_", rel)
    row = {"file": rel, "status": "ok", "problems": []}
    code, err, stats = render(args.visbuf, path, os.path.join(work, stem + ".json"), args.timeout)
    row["warnings"] = warnings_of(err)
    row["renderCode"] = code
    if code == 0:
        row["psnr"] = psnr_of(stats)
        row["covered"] = stats.get("coveredPixels", 0)
        row["triangles"] = stats.get("trianglesDrawn", 0)
        if row["psnr"] < args.min_psnr:
            row["problems"].append("render %.1f dB against forward (< %.1f)" % (row["psnr"], args.min_psnr))
    elif code == 1:
        row["status"] = "refused"
        row["message"] = first_error(err)
        return row
    else:
        row["problems"].append("render: " + ("exit %s" % code if code is not None else "") + " " + first_error(err))
        return row
    pack = os.path.join(work, stem + ".vbp")
    bake_json = os.path.join(work, stem + ".bake.json")
    code, err = run([args.visbuf, "bake", path, "-o", pack, "--json", bake_json], args.timeout)
    row["bakeCode"] = code
    if code != 0:
        row["problems"].append("bake: exit %s %s" % (code, first_error(err)))
        return row
    row["packBytes"] = os.path.getsize(pack)
    code, err, stats = render(args.visbuf, pack, os.path.join(work, stem + ".pack.json"), args.timeout)
    if code != 0:
        row["problems"].append("pack render: exit %s %s" % (code, first_error(err)))
        return row
    row["packPsnr"] = psnr_of(stats)
    if row["packPsnr"] < args.min_psnr:
        row["problems"].append("pack render %.1f dB against forward (< %.1f)" % (row["packPsnr"], args.min_psnr))
    os.remove(pack)
    return row


def read_expectations(path):
    refusals = []
    if path and os.path.exists(path):
        with open(path) as f:
            for line in f:
                line = line.strip()
                if not line or line.startswith("#"):
                    continue
                kind, rel, pattern = line.split(None, 2)
                if kind != "refuse":
                    raise SystemExit("%s: unknown expectation '%s'" % (path, kind))
                refusals.append((rel, re.compile(pattern)))
    return refusals


def db(v):
    return "exact" if v is None or v >= 998 else "%.1f" % v


def cell(text, limit=110):
    text = text.replace("|", "\\|").replace("\n", " ")
    return text if len(text) <= limit else text[:limit - 3] + "..."


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("folder")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--visbuf", default=os.path.join(root, "build", "tools", "visbuf"))
    ap.add_argument("--out", help="write the Markdown table here (atomically)")
    ap.add_argument("--json", help="write the rows as JSON here")
    ap.add_argument("--expect", help="expected refusals (default: FOLDER/conformance-expect.txt when present)")
    ap.add_argument("--min-psnr", type=float, default=40.0)
    ap.add_argument("--timeout", type=int, default=300)
    ap.add_argument("--jobs", type=int, default=max(1, min(2, os.cpu_count() or 1)))
    args = ap.parse_args()
    expect = args.expect or os.path.join(args.folder, "conformance-expect.txt")
    refusals = read_expectations(expect)
    files = []
    for root, dirs, names in os.walk(args.folder):
        dirs.sort()
        for n in sorted(names):
            if n.lower().endswith((".gltf", ".glb")):
                files.append(os.path.relpath(os.path.join(root, n), args.folder))
    with tempfile.TemporaryDirectory(prefix="visbuf-conformance-") as work:
        with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
            rows = list(pool.map(lambda rel: sweep_one(args, rel, work), files))
    failed = 0
    for row in rows:
        expected = [p for rel, p in refusals if rel == row["file"]]
        if row["status"] == "refused":
            if not expected:
                row["problems"].append("refused unexpectedly: " + row["message"])
            elif not any(p.search(row["message"]) for p in expected):
                row["problems"].append("refused with another message: " + row["message"])
        elif expected:
            row["problems"].append("expected a refusal (%s) but it loaded" % expected[0].pattern)
        if row["problems"]:
            row["status"] = "FAIL"
            failed += 1
    lines = ["| file | result | render vs forward (dB) | pack vs forward (dB) | pack size | warnings | note |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        note = "; ".join(r["problems"]) or r.get("message", "") or (r["warnings"][0] if r["warnings"] else "")
        size = "%.1f KB" % (r["packBytes"] / 1024.0) if "packBytes" in r else "-"
        lines.append("| %s | %s | %s | %s | %s | %d | %s |" % (
            cell(r["file"], 80), r["status"], db(r.get("psnr")) if "psnr" in r else "-",
            db(r.get("packPsnr")) if "packPsnr" in r else "-", size, len(r["warnings"]), cell(note)))
    ok = sum(r["status"] == "ok" for r in rows)
    refused = sum(r["status"] == "refused" for r in rows)
    summary = "%d files: %d render and bake, %d refused as expected, %d failed (PSNR bar %.1f dB, %s)" % (
        len(rows), ok, refused, failed, args.min_psnr, SIZE)
    text = "\n".join(lines) + "\n\n" + summary + "\n"
    if args.out:
        tmp = args.out + ".tmp"
        with open(tmp, "w") as f:
            f.write(text)
        os.replace(tmp, args.out)
    if args.json:
        tmp = args.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump(rows, f, indent=1)
        os.replace(tmp, args.json)
    print(text)
    for r in rows:
        if r["status"] == "FAIL":
            print("conformance: FAIL %s: %s" % (r["file"], "; ".join(r["problems"])), file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
