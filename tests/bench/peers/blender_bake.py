"""Bake a glTF scene's diffuse irradiance with Blender Cycles (CPU), headless.

Run inside Blender (Debian 12: blender 3.4.1):

  blender -b --factory-startup --python tests/bench/peers/blender_bake.py -- \
      --scene scenes/cornell_box.gltf --out DIR --resolution 64 --bounces 4 \
      --runs 1@3,16@3,64@3,256@3,4096@1 [--sky R,G,B] [--t0 EPOCH_SECONDS] \
      [--materials lambert|principled]

What it does (README.md next to this file explains the conversions):

  1. imports the glTF with Blender's own importer (io_scene_gltf2);
  2. makes the materials match Luxel's transport model (default
     `--materials lambert`): every material becomes a Diffuse BSDF (roughness
     0 = Lambert) with the importer's base colour, plus an Emission shader with
     the importer's emission colour x strength (= glTF emissiveFactor x
     KHR_materials_emissive_strength) that is zeroed on back faces unless the
     glTF material is doubleSided (Blender emits from both sides, Luxel from
     the front only). Only valid for metallic = 0, roughness = 1 materials,
     which Luxel also shades as pure Lambert; anything else is refused.
     `--materials principled` keeps the importer's Principled BSDF (to measure
     what the material model alone changes);
  3. sets the world to a constant background of colour --sky, strength 1
     (radiance R,G,B in W/m^2/sr, as Luxel's --sky), or black;
  4. Cycles CPU, all threads, no clamping, no light threshold, no adaptive
     sampling, no denoising; max/diffuse/glossy/transmission bounces = --bounces;
  5. bakes type DIFFUSE, pass filter {DIRECT, INDIRECT} (no COLOR) into one
     float image of --resolution^2 through the lightmap UV map (glTF
     TEXCOORD_1 = the importer's second UV map, "UVMap.001"), margin 0, once
     per entry of --runs (SAMPLES@SEED), timing each bpy.ops.object.bake call;
  6. writes DIR/blender_s<SAMPLES>_seed<SEED>.exr (RGBA float32, row 0 = top,
     RGB multiplied by pi so it is irradiance E in W/m^2 like Luxel's:
     Blender's diffuse pass without colour is E / pi) and DIR/blender.json
     with the timings.
"""
import argparse
import json
import math
import os
import sys
import time
import warnings

T_SCRIPT = time.time()

import numpy as np  # noqa: E402

# Debian's blender 3.4.1 glTF importer still uses np.bool, which Debian 12's
# numpy 1.24 removed (AttributeError on import). Restore the alias.
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    if not hasattr(np, "bool"):
        np.bool = bool

import bpy  # noqa: E402


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="blender_bake.py")
    ap.add_argument("--scene", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--resolution", type=int, default=64)
    ap.add_argument("--bounces", type=int, default=4)
    ap.add_argument("--runs", default="64",
                    help="comma-separated bakes in order, SAMPLES or SAMPLES@SEED (seed default 1)")
    ap.add_argument("--sky", default=None, help="constant sky radiance R,G,B")
    ap.add_argument("--materials", choices=["lambert", "principled"], default="lambert")
    ap.add_argument("--uv-map", default=None, help="UV map name (default: the second one)")
    ap.add_argument("--warmup", action="store_true",
                    help="one 1-spp bake before the runs, timed apart (first-bake costs)")
    ap.add_argument("--t0", type=float, default=None,
                    help="epoch seconds when the caller started blender (startup time)")
    return ap.parse_args(argv)


def to_lambert(mat):
    """Replace the importer's Principled BSDF by Lambert (+ one-sided emission)."""
    nt = mat.node_tree
    bsdf = next((n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"), None)
    out = next((n for n in nt.nodes if n.type == "OUTPUT_MATERIAL"), None)
    if bsdf is None or out is None:
        raise SystemExit(f"material {mat.name}: no Principled BSDF from the glTF importer")
    metallic = bsdf.inputs["Metallic"]
    rough = bsdf.inputs["Roughness"]
    if metallic.is_linked or rough.is_linked or metallic.default_value > 0.0 or rough.default_value < 1.0:
        raise SystemExit(f"material {mat.name}: metallic {metallic.default_value} roughness "
                         f"{rough.default_value}: only metallic=0, roughness=1 (Lambert in Luxel) "
                         "is supported by --materials lambert")
    base = bsdf.inputs["Base Color"]
    emis = bsdf.inputs["Emission"]
    strength = float(bsdf.inputs["Emission Strength"].default_value)
    info = {"base_color": [round(x, 6) for x in list(base.default_value)[:3]],
            "emission_color": [round(x, 6) for x in list(emis.default_value)[:3]],
            "emission_strength": strength,
            "double_sided": not mat.use_backface_culling}

    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Roughness"].default_value = 0.0  # Oren-Nayar sigma 0 = Lambert
    if base.is_linked:   # base colour texture: keep it
        nt.links.new(base.links[0].from_socket, diffuse.inputs["Color"])
    else:
        diffuse.inputs["Color"].default_value = base.default_value
    shader = diffuse.outputs["BSDF"]
    if emis.is_linked:
        raise SystemExit(f"material {mat.name}: emissive textures are not supported here")
    if max(list(emis.default_value)[:3]) * strength > 0.0:
        em = nt.nodes.new("ShaderNodeEmission")
        em.inputs["Color"].default_value = emis.default_value
        if info["double_sided"]:
            em.inputs["Strength"].default_value = strength
        else:  # Luxel emitters are one-sided: strength * (1 - backfacing)
            geo = nt.nodes.new("ShaderNodeNewGeometry")
            front = nt.nodes.new("ShaderNodeMath")
            front.operation = "SUBTRACT"
            front.inputs[0].default_value = 1.0
            nt.links.new(geo.outputs["Backfacing"], front.inputs[1])
            scale = nt.nodes.new("ShaderNodeMath")
            scale.operation = "MULTIPLY"
            scale.inputs[1].default_value = strength
            nt.links.new(front.outputs["Value"], scale.inputs[0])
            nt.links.new(scale.outputs["Value"], em.inputs["Strength"])
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(shader, add.inputs[0])
        nt.links.new(em.outputs["Emission"], add.inputs[1])
        shader = add.outputs["Shader"]
    nt.nodes.remove(bsdf)
    nt.links.new(shader, out.inputs["Surface"])
    return info


def write_exr(path, img, res):
    px = np.empty(res * res * 4, np.float32)
    img.pixels.foreach_get(px)
    # Blender stores rows bottom-up (row 0 = Blender v 0 = glTF v 1): flip so
    # row 0 is the top row = glTF TEXCOORD_1 v = 0, Luxel's convention.
    # Blender's diffuse pass without colour is E / pi: multiply RGB by pi.
    px = np.flipud(px.reshape(res, res, 4)).copy()
    px[..., :3] *= math.pi
    try:
        import OpenImageIO as oiio
    except ImportError:
        oiio = None
    if oiio is not None:
        spec = oiio.ImageSpec(res, res, 4, "float")
        spec.attribute("compression", "zip")
        o = oiio.ImageOutput.create(path)
        if o is None or not o.open(path, spec):
            raise RuntimeError(oiio.geterror())
        o.write_image(px)
        o.close()
    else:  # Blender's own writer (it flips back to bottom-up in memory)
        tmp = bpy.data.images.new("out", res, res, alpha=True, float_buffer=True)
        tmp.pixels.foreach_set(np.flipud(px).ravel())
        tmp.filepath_raw = path
        tmp.file_format = "OPEN_EXR"
        tmp.save()
        bpy.data.images.remove(tmp)


def main():
    a = parse_args()
    os.makedirs(a.out, exist_ok=True)
    t_import0 = time.time()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(a.scene))
    t_import = time.time() - t_import0

    t_setup0 = time.time()
    scene = bpy.context.scene
    meshes = [o for o in scene.objects if o.type == "MESH"]
    if not meshes:
        raise SystemExit("no meshes imported")
    lights = [o for o in scene.objects if o.type == "LIGHT"]
    if lights:
        raise SystemExit(f"{len(lights)} punctual lights: this harness compares emissive/sky "
                         "lighting only (light unit conversions are not handled)")
    uv_names = set()
    for o in meshes:
        if len(o.data.uv_layers) < 2 and a.uv_map is None:
            raise SystemExit(f"object {o.name}: no second UV map (glTF TEXCOORD_1)")
        name = a.uv_map or o.data.uv_layers[1].name
        o.data.uv_layers.active = o.data.uv_layers[name]
        uv_names.add(name)
    if len(uv_names) != 1:
        raise SystemExit(f"lightmap UV maps differ between objects: {sorted(uv_names)}")
    uv_name = uv_names.pop()

    img = bpy.data.images.new("lightmap", a.resolution, a.resolution, alpha=True, float_buffer=True)
    img.colorspace_settings.name = "Linear"
    materials = {}
    for m in bpy.data.materials:
        if not m.use_nodes or m.users == 0:
            continue
        if a.materials == "lambert":
            materials[m.name] = to_lambert(m)
        tex = m.node_tree.nodes.new("ShaderNodeTexImage")
        tex.image = img
        for n in m.node_tree.nodes:
            n.select = False
        tex.select = True
        m.node_tree.nodes.active = tex   # the bake target

    world = bpy.data.worlds.new("luxel_sky")
    scene.world = world
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    sky = [float(x) for x in a.sky.split(",")] if a.sky else [0.0, 0.0, 0.0]
    bg.inputs["Color"].default_value = (*sky, 1.0)
    bg.inputs["Strength"].default_value = 1.0

    c = scene.cycles
    scene.render.engine = "CYCLES"
    c.device = "CPU"
    scene.render.threads_mode = "AUTO"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.time_limit = 0.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0      # the factory default 10 would clip bright paths
    c.light_sampling_threshold = 0.0
    c.blur_glossy = 0.0
    c.max_bounces = a.bounces
    c.diffuse_bounces = a.bounces
    c.glossy_bounces = a.bounces
    c.transmission_bounces = a.bounces
    c.transparent_max_bounces = 8
    c.volume_bounces = 0
    c.min_light_bounces = 0
    c.min_transparent_bounces = 0
    bk = scene.render.bake
    bk.use_pass_direct = True
    bk.use_pass_indirect = True
    bk.use_pass_color = False
    bk.margin = 0
    bk.target = "IMAGE_TEXTURES"
    bk.use_clear = True

    bpy.ops.object.select_all(action="DESELECT")
    for o in meshes:
        o.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]
    t_setup = time.time() - t_setup0

    runs = []
    for tok in a.runs.split(","):
        if tok:
            spp, _, seed = tok.partition("@")
            runs.append((int(spp), int(seed or 1)))
    bakes = []
    warmup_s = None
    if a.warmup:
        c.samples, c.seed = 1, 9
        t = time.time()
        bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=0,
                            use_clear=True, uv_layer=uv_name, target="IMAGE_TEXTURES")
        warmup_s = time.time() - t
        print(f"blender_bake: warm-up 1 spp: {warmup_s:8.3f} s", flush=True)
    for i, (spp, seed) in enumerate(runs):
        c.samples = spp
        c.seed = seed
        t = time.time()
        bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=0,
                            use_clear=True, uv_layer=uv_name, target="IMAGE_TEXTURES")
        dt = time.time() - t
        # a SAMPLES@SEED repeated in --runs (a warm-up bake) gets its own file
        tag = "" if (spp, seed) not in runs[:i] else f"_run{i}"
        name = f"blender_s{spp}_seed{seed}{tag}.exr"
        write_exr(os.path.join(a.out, name), img, a.resolution)
        bakes.append({"samples": spp, "seed": seed, "seconds": dt, "file": name})
        print(f"blender_bake: {spp:6d} spp seed {seed}: {dt:8.3f} s", flush=True)

    info = {
        "blender_version": bpy.app.version_string,
        "scene": a.scene, "resolution": a.resolution, "bounces": a.bounces,
        "sky": sky, "materials": a.materials, "uv_map": uv_name,
        "objects": len(meshes), "threads": scene.render.threads,
        "sampling_pattern": c.sampling_pattern,
        "startup_s": (T_SCRIPT - a.t0) if a.t0 else None,
        "import_s": t_import, "setup_s": t_setup, "warmup_s": warmup_s,
        "material_conversion": materials,
        "bakes": bakes,
    }
    with open(os.path.join(a.out, "blender.json"), "w") as f:
        json.dump(info, f, indent=1)


main()
