#!/usr/bin/env python3
"""No pass makes the CPU device compile a shader while the frame runs.

lavapipe in Mesa 22 (Debian 12's) inlines push constants and uniform-buffer values into a compute shader that
branches on such values alone, and keeps no variants: it optimises, compiles and links the shader again at every
bind (shaders/uniform_branch.glsl). With its shader cache on that costs a cache load per dispatch (about 3.5 ms a
micro-raster dispatch, whatever it draws); with the cache off a whole compile (150-190 ms). So each configuration
is rendered twice, with MESA_SHADER_CACHE_DISABLE=false and =true, and no pass's median GPU time may be more than
MARGIN_MS longer without the cache: a pass that recompiles per bind is 100+ ms longer, one that does not is the
same within the machine's noise (the frames are small: 3,000 kittens at 320x240, every pass a few ms).

Configurations: the default frame (occlusion, both micro-raster phases, covered-pixel shading), the ubershader
with tiled point lights, every light at every pixel, the forward path with lights, material classification, 4x
MSAA, and the G-buffer path.

usage: cli_shader_variants.py VISBUF OUT_FOLDER
"""
import json
import os
import subprocess
import sys

MARGIN_MS = 40.0
KITTEN = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "assets", "Kitten", "kitten.glb")
FIELD = ["--scene", "field", "--mesh", KITTEN, "--objects", "3000"]
CONFIGS = {
    "default": FIELD,
    "uber, tiled lights": FIELD + ["--shading", "uber", "--lights", "20"],
    "covered, every light": FIELD + ["--lights", "20", "--all-lights"],
    # (the forward path draws every triangle in the hardware raster: 200 kittens keep it a few ms)
    "forward, lights": FIELD[:-1] + ["200", "--path", "forward", "--lights", "20"],
    "classified": FIELD + ["--shading", "classified"],
    "msaa 4": ["--scene", "city", "--objects", "3000", "--msaa", "4"],
    "gbuffer": FIELD + ["--path", "gbuffer"],
}


def pass_times(visbuf, out, name, args, cache_off):
    path = os.path.join(out, f"{name.replace(' ', '_').replace(',', '')}_{'off' if cache_off else 'on'}.json")
    env = dict(os.environ, MESA_SHADER_CACHE_DISABLE="true" if cache_off else "false")
    r = subprocess.run([visbuf, "render", "--device", "cpu", *args, "--size", "320x240", "--frames", "4", "-o", "",
                        "--json", path], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.exit(f"{name}: render failed ({r.returncode}): {r.stderr}")
    with open(path) as f:
        return json.load(f)["passMs"]


def main():
    visbuf, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    failures = []
    for name, args in CONFIGS.items():
        on = pass_times(visbuf, out, name, args, cache_off=False)
        off = pass_times(visbuf, out, name, args, cache_off=True)
        worst = max(on, key=lambda p: off.get(p, 0.0) - on[p])
        print(f"{name}: {len(on)} passes; largest difference without the cache: {worst} "
              f"{on[worst]:.2f} -> {off.get(worst, 0.0):.2f} ms")
        for p, ms in on.items():
            if off.get(p, 0.0) > ms + MARGIN_MS:
                failures.append(f"{name}: pass '{p}' takes {off[p]:.1f} ms without the shader cache against "
                                f"{ms:.1f} ms with it: a shader is compiled while the frame runs")
    if failures:
        sys.exit("cli_shader_variants: " + "; ".join(failures))
    print("cli_shader_variants: ok")


if __name__ == "__main__":
    main()
