#!/usr/bin/env python3
"""A glTF rendered directly shows its textures, as the pack baked from it does (visbuf::loadScene, load_scene.h).

Fox (a skinned mesh whose one material is an orange base colour texture), with --instances 2 (copies on a grid,
the path where the textures were once lost: white foxes):
  1. `visbuf bake Fox.glb -o Fox.vbp` (default options);
  2. `visbuf render --scene X --instances 2 --size 160x120 --validation` of Fox.glb and of Fox.vbp, the camera
     close to the copies;
  3. the same image: `oiiotool --diff` PSNR >= SAME_PSNR dB (both load the same meshes and texels: measured inf,
     identical bytes on lavapipe);
  4. textured: the mean over the image of max(R - B, 0) (oiiotool --chsum weight 1,0,-1 then --clamp) is at
     least WARM. The background and an untextured fox (grey surfaces under white light and a bluish ambient)
     give exactly 0 (measured with a --no-textures pack); the textured foxes 0.0091. So a direct render that lost
     its textures fails 4 even when the pack lost them too.
(The unit test LoadSceneTest.GltfEqualsThePackBakedFromIt compares the two scenes field by field, CesiumMilkTruck
included.)

usage: cli_render_gltf_textured.py VISBUF ASSETS OUT_FOLDER
"""
import os
import re
import subprocess
import sys

SAME_PSNR = 60.0
WARM = 0.002
ASSET = "Fox/glTF-Binary/Fox.glb"
# The copies stand near x = -3 and x = 0 at z = -3 (makeAnimatedField's grid, spacing 3): seen from the front.
RENDER = ["--instances", "2", "--size", "160x120", "--validation", "--camera-pos", "-1.5,1.0,0",
          "--camera-target", "-1.5,0.1,-3"]


def fail(message):
    print(f"cli_render_gltf_textured: FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        fail(f"{' '.join(cmd)} exited {r.returncode}:\n{r.stdout}{r.stderr}")
    if "validation:" in r.stderr:
        fail(f"{' '.join(cmd)}: validation message:\n{r.stderr}")
    return r


def diff(a, b):
    """(PSNR dB, mean error) of two images by oiiotool --diff (inf for identical images)."""
    r = subprocess.run(["oiiotool", "-v", a, b, "--diff"], capture_output=True, text=True, timeout=60)
    psnr = re.search(r"Peak SNR = (\S+)", r.stdout)
    mean = re.search(r"Mean error = (\S+)", r.stdout)
    if not psnr or not mean:
        fail(f"oiiotool --diff {a} {b} printed no PSNR / mean error:\n{r.stdout}{r.stderr}")
    return float(psnr.group(1)), float(mean.group(1))


def warmth(image):
    """Mean over the image of max(R - B, 0), in [0, 1]."""
    r = subprocess.run(["oiiotool", image, "--chsum:weight=1,0,-1,0", "--clamp:min=0", "--printstats"],
                       capture_output=True, text=True, timeout=60)
    m = re.search(r"Stats Avg: (\S+)", r.stdout)
    if not m:
        fail(f"oiiotool --printstats {image} printed no average:\n{r.stdout}{r.stderr}")
    return float(m.group(1))


def main():
    if len(sys.argv) != 4:
        fail("usage: cli_render_gltf_textured.py VISBUF ASSETS OUT_FOLDER")
    visbuf, assets, out = sys.argv[1:]
    os.makedirs(out, exist_ok=True)
    source = os.path.join(assets, ASSET)
    if not os.path.exists(source):
        fail(f"asset missing from the checkout's assets/: {source}")
    pack = os.path.join(out, "Fox.vbp")
    run([visbuf, "bake", source, "-o", pack])
    direct, baked = os.path.join(out, "direct.png"), os.path.join(out, "pack.png")
    run([visbuf, "render", "--scene", source, *RENDER, "-o", direct])
    run([visbuf, "render", "--scene", pack, *RENDER, "-o", baked])
    psnr, mean = diff(direct, baked)
    warm = warmth(direct)
    print(f"Fox x2: direct vs pack {psnr} dB (mean error {mean}); warmth {warm}")
    if not psnr >= SAME_PSNR:
        fail(f"the glTF rendered directly is {psnr} dB from its pack's render (>= {SAME_PSNR} expected): "
             f"{direct} {baked}")
    if not warm >= WARM:
        fail(f"the glTF rendered directly looks untextured: mean max(R - B, 0) {warm} (>= {WARM} expected): {direct}")
    print("cli_render_gltf_textured: ok")


if __name__ == "__main__":
    main()
