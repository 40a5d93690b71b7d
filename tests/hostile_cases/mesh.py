"""Meshes that stress the mesh build (dedup, LOD chain and its measured error, meshlets): stacked copies of one
large triangle (once a heap overflow of the error grid), fan discs (once quadratic in the grid and the meshlet
builder), a position-less accessor of 2^24 - 1 vertices from a 1 KB file (once ~100 hours of meshlet building),
coincident vertices, slivers, one huge triangle among small ones. Each through `bake`, `render --scene` and
`render --mesh` (64x64, lavapipe or a GPU): a correct result or a clean error, within the suite's caps."""
import json
import math
import os
import random
import struct


def _pad4(b, fill=b"\0"):
    return b + fill * (-len(b) % 4)


def glb(positions, indices=None, normals=None, extra_doc=None):
    """A GLB of one mesh with one primitive: positions (list of xyz), optional u32 indices and normals."""
    blob = b""
    views, accessors = [], []

    def add(data, count, type_, component, target, minmax=None):
        nonlocal blob
        blob = _pad4(blob)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data), "target": target})
        acc = {"bufferView": len(views) - 1, "componentType": component, "count": count, "type": type_}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        blob += data
        return len(accessors) - 1

    flat = [c for p in positions for c in p]
    lo = [min(p[k] for p in positions) for k in range(3)]
    hi = [max(p[k] for p in positions) for k in range(3)]
    attributes = {"POSITION": add(struct.pack(f"<{len(flat)}f", *flat), len(positions), "VEC3", 5126, 34962,
                                  (lo, hi))}
    if normals is not None:
        nflat = [c for n in normals for c in n]
        attributes["NORMAL"] = add(struct.pack(f"<{len(nflat)}f", *nflat), len(normals), "VEC3", 5126, 34962)
    prim = {"attributes": attributes}
    if indices is not None:
        prim["indices"] = add(struct.pack(f"<{len(indices)}I", *indices), len(indices), "SCALAR", 5125, 34963)
    doc = {"asset": {"version": "2.0"}, "buffers": [{"byteLength": len(_pad4(blob))}], "bufferViews": views,
           "accessors": accessors, "meshes": [{"primitives": [prim]}], "nodes": [{"mesh": 0}],
           "scenes": [{"nodes": [0]}], "scene": 0}
    if extra_doc:
        doc.update(extra_doc)
    js = _pad4(json.dumps(doc, separators=(",", ":")).encode(), b" ")
    body = struct.pack("<I", len(js)) + b"JSON" + js
    blob = _pad4(blob)
    body += struct.pack("<I", len(blob)) + b"BIN\0" + blob
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def stacked(copies):
    """`copies` copies of one large triangle sharing its three vertices (the issue's 790 KB file: 65,600)."""
    return glb([(-100, -100, 0), (100, -100, 0), (0, 100, 0)], [0, 1, 2] * copies)


def stacked_distinct(copies):
    """Copies of one triangle, each with its own vertices and its own normal: nothing merges them, and every
    centroid is the same point."""
    pos, nrm, idx = [], [], []
    for i in range(copies):
        a = 2 * math.pi * i / copies
        n = (math.cos(a) * 0.5, math.sin(a) * 0.5, 0.8)
        pos += [(-1, -1, 0), (1, -1, 0), (0, 1, 0)]
        nrm += [n, n, n]
        idx += [3 * i, 3 * i + 1, 3 * i + 2]
    return glb(pos, idx, nrm)


def fan(n, centre_copies=False):
    """A flat disc of n triangles around one centre vertex (or, with centre_copies, one coincident centre vertex
    per triangle, each with its own normal: thousands of vertices at one position)."""
    rim = [(math.cos(2 * math.pi * i / n), math.sin(2 * math.pi * i / n), 0.0) for i in range(n)]
    if not centre_copies:
        return glb([(0.0, 0.0, 0.0)] + rim, [k for i in range(n) for k in (0, 1 + i, 1 + (i + 1) % n)])
    pos = rim + [(0.0, 0.0, 0.0)] * n
    nrm = [(0.0, 0.0, 1.0)] * n + [(math.cos(i * 0.001) * 0.3, math.sin(i * 0.001) * 0.3, 0.9) for i in range(n)]
    return glb(pos, [k for i in range(n) for k in (n + i, i, (i + 1) % n)], nrm)


def slivers(n, seed=1):
    """Long thin triangles crossing a cube along random diagonals: every bounding box is most of the cube."""
    rng = random.Random(seed)
    pos, idx = [], []
    for i in range(n):
        a = (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1))
        off = tuple(rng.uniform(-1e-3, 1e-3) for _ in range(3))
        pos += [a, tuple(-c for c in a), tuple(c * 0.5 + o for c, o in zip(a, off))]
        idx += [3 * i, 3 * i + 1, 3 * i + 2]
    return glb(pos, idx)


def huge_among_small(side):
    """A side x side grid of small triangles with one triangle 10^4 times larger across it."""
    pos = [(float(x), float(y), math.sin(x + y) * 0.3) for y in range(side + 1) for x in range(side + 1)]
    idx = []
    for y in range(side):
        for x in range(side):
            i = y * (side + 1) + x
            idx += [i, i + 1, i + side + 1, i + 1, i + side + 2, i + side + 1]
    h = len(pos)
    pos += [(-1e4, -1e4, 3.0), (1e4, -1e4, 3.0), (0.0, 1e4, 3.0)]
    idx += [h, h + 1, h + 2]
    return glb(pos, idx)


def positionless(count, sparse_values=3):
    """A 1 KB .gltf: POSITION has no bufferView (zeros) and `sparse_values` sparse values, `count` vertices, no
    indices: count / 3 triangles, almost all of them at the origin."""
    idx = struct.pack(f"<{sparse_values}I", *[i * 7 for i in range(sparse_values)])
    val = struct.pack(f"<{3 * sparse_values}f", *[float(c) for i in range(sparse_values) for c in (i, i % 2, 1)])
    blob = idx + val
    import base64
    doc = {"asset": {"version": "2.0"},
           "buffers": [{"byteLength": len(blob),
                        "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(idx)},
                           {"buffer": 0, "byteOffset": len(idx), "byteLength": len(val)}],
           "accessors": [{"componentType": 5126, "count": count, "type": "VEC3",
                          "min": [0, 0, 0], "max": [float(sparse_values), 1, 1],
                          "sparse": {"count": sparse_values, "indices": {"bufferView": 0, "componentType": 5125},
                                     "values": {"bufferView": 1}}}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}
    return json.dumps(doc).encode()


def cases(ctx):
    def write(case, name, data):
        root = ctx.folder(case)
        path = os.path.join(root, name)
        with open(path, "wb") as f:
            f.write(data)
        return root, path

    def bake(case, name, data_fn, error=None):
        root, path = write(case, name, data_fn())
        out = os.path.join(root, "out.vbp")
        outcome = ctx.visbuf_run(["bake", path, "-o", out], root)
        if error:
            if ctx.expect_error(case, outcome, error) and os.path.exists(out):
                ctx.fail(case, "a pack was written")
        else:
            ctx.expect_ok(case, outcome,
                          lambda: None if os.path.getsize(out) > 0 else "no pack written")

    def render(case, name, data_fn, flag, error=None):
        root, path = write(case, name, data_fn())
        out = os.path.join(root, "out.json")
        outcome = ctx.visbuf_run(["render", flag, path, "--size", "64x64", "--frames", "1", "-o", "",
                                  "--json", out], root)
        if error:
            ctx.expect_error(case, outcome, error)
        else:
            ctx.expect_ok(case, outcome, lambda: None if os.path.exists(out) else "no stats written")

    inputs = {
        "stacked_65600": ("stacked.glb", lambda: stacked(65600)),
        "fan_60k": ("fan60k.glb", lambda: fan(60000)),
        "fan_120k": ("fan120k.glb", lambda: fan(120000)),
        "positionless_2p24": ("positionless.gltf", lambda: positionless((1 << 24) - 1)),
        "positionless_2p20": ("positionless.gltf", lambda: positionless(1 << 20)),
        "stacked_distinct_60k": ("stacked_distinct.glb", lambda: stacked_distinct(60000)),
        "coincident_centres_60k": ("coincident.glb", lambda: fan(60000, centre_copies=True)),
        "slivers_60k": ("slivers.glb", lambda: slivers(60000)),
        "huge_among_small": ("huge.glb", lambda: huge_among_small(200)),
    }
    # A file that declares 2^24 - 1 vertices it does not hold is refused before anything is decoded; at the limit
    # (2^20) it is built.
    refused = {"positionless_2p24": r"accessor 0.*count 16777215 without a bufferView .*exceeds the limit of 1048576"}
    for case, (name, fn) in inputs.items():
        yield f"bake_{case}", (lambda case=case, name=name, fn=fn:
                               bake(f"bake_{case}", name, fn, refused.get(case)))
    # The renders build the same meshes in the render process (the scene import, and the field's instanced mesh).
    # (fan_60k, not 120k: the bakes above show the build is linear; each render also pays lavapipe's start-up.)
    for case in ("stacked_65600", "fan_60k", "positionless_2p24", "positionless_2p20", "stacked_distinct_60k",
                 "coincident_centres_60k"):
        name, fn = inputs[case]
        yield (f"render_scene_{case}", lambda case=case, name=name, fn=fn:
               render(f"render_scene_{case}", name, fn, "--scene", refused.get(case)))
        yield (f"render_mesh_{case}", lambda case=case, name=name, fn=fn:
               render(f"render_mesh_{case}", name, fn, "--mesh", refused.get(case)))
