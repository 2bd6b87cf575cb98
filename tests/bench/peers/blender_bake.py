"""Bake a glTF scene's diffuse irradiance with Blender Cycles (CPU), headless.

Run inside Blender (Debian 12: blender 3.4.1):

  blender -b --factory-startup --python tests/bench/peers/blender_bake.py -- \
      --scene scenes/cornell_box.gltf --out DIR --resolution 64 --bounces 4 \
      --runs 1@3,16@3,64@3,256@3,4096@1 [--sky R,G,B] [--sun X,Y,Z,E,DEG] \
      [--directional-radius DEG] [--t0 EPOCH_SECONDS] [--materials matched|principled]
      [--diffuse-weight nv|vh-average] [--denoise oidn [--denoise-filter RT|RTLightmap]]

or with Blender as a Python module (PyPI bpy 5.0.1, tests/support/bpy-venv.sh;
no blender binary, the same arguments without "--"):

  ~/.cache/luxel/bpy-5.0.1/bin/python tests/bench/peers/blender_bake.py --scene ...

Differences between the versions are looked up, not assumed: the importer's
lighting-mode option, the linear colour space's name, the Principled
emission socket, the colour mix node, the spot attenuation (README.md).

What it does (README.md next to this file explains the conversions):

  1. imports the glTF with Blender's own importer (io_scene_gltf2), lighting
     mode COMPAT ("Unitless"): point/spot energy = 4 pi x glTF intensity,
     sun strength = glTF intensity, i.e. radiant intensity (W/sr) and
     irradiance (W/m^2) 1:1 as Luxel reads them; checked against the file;
  2. makes the lights match Luxel's: point and spot radius 0 (the importer
     leaves Blender's 0.25 m soft radius), sun angle = 2 x --directional-radius;
     spots get a hard cone (blend 0, size = 2 x outerConeAngle) and a light
     node tree whose strength is glTF's falloff over Cycles' own (below);
  3. makes the materials match Luxel's BSDF (default `--materials matched`):
     Lambert when no material of the scene needs the GGX layer (Luxel then
     compiles it out), else glTF 2.0 Appendix B's mix by metallic of a metal
     (Multiscatter GGX, Schlick F(base)) and a dielectric (Lambert x (1 - F)
     + Multiscatter GGX, Schlick F(0.04)), F at the shading normal, from the
     importer's base colour, metallic and roughness sockets (textures kept),
     plus an Emission shader (emission colour x strength, zeroed on back faces
     unless the glTF material is doubleSided: Cycles emits from both sides,
     Luxel from the front only). `--materials principled` keeps the
     importer's Principled BSDF (what the material model alone changes).
     In both, the baked point itself sees a white Lambert surface (Light Path
     "Is Camera Ray", set on bake paths' first vertex): the pass is then E/pi
     whatever the receiver's material, as Luxel's irradiance lightmap;
  4. sets the world to a constant background of colour --sky, strength 1
     (radiance R,G,B in W/m^2/sr, as Luxel's --sky), or black; --sun adds a
     sun lamp like Luxel's --sun/--sun-illuminance/--sun-radius;
  5. Cycles CPU, all threads, no clamping, no light threshold, no adaptive
     sampling, no denoising; max/diffuse/glossy/transmission bounces = --bounces;
  6. bakes type DIFFUSE, pass filter {DIRECT, INDIRECT} (no COLOR) into one
     float image of --resolution^2 through the lightmap UV map (glTF
     TEXCOORD_1 = the importer's second UV map, "UVMap.001"), margin 0, once
     per entry of --runs (SAMPLES@SEED), timing each bpy.ops.object.bake call;
  7. writes DIR/blender_s<SAMPLES>_seed<SEED>.exr (RGBA float32, row 0 = top,
     RGB multiplied by pi so it is irradiance E in W/m^2 like Luxel's:
     Blender's diffuse pass without colour is E / pi) and DIR/blender.json
     with the timings and the Cycles settings left at their defaults (light
     tree, sampling pattern); --denoise oidn adds each bake denoised by Open
     Image Denoise (oidn_lightmap.py), blender_s<SAMPLES>_seed<SEED>_oidn.exr,
     its seconds apart from the bake's.
"""
# Over 500 lines: it runs inside Blender as one script (scene import, the matched material graph, the bake, the EXR writer) for both Blender versions.
import argparse
import json
import math
import os
import sys
import time
import warnings

import numpy as np  # noqa: E402

# Debian's blender 3.4.1 glTF importer still uses np.bool, which Debian 12's
# numpy 1.24 removed (AttributeError on import). Restore the alias.
with warnings.catch_warnings():
    warnings.simplefilter("ignore")
    if not hasattr(np, "bool"):
        np.bool = bool

import bpy  # noqa: E402

# as bpy 5.0.1's module (`python blender_bake.py ...`) Blender starts here,
# at `import bpy`; inside the blender binary it started before the script
T_STARTED = time.time()
AS_MODULE = not bpy.app.binary_path   # the PyPI bpy module: no blender binary


def parse_args():
    # blender -b ... --python blender_bake.py -- ARGS: ours follow "--";
    # python blender_bake.py ARGS (bpy module): sys.argv is ours
    if "--" in sys.argv:
        argv = sys.argv[sys.argv.index("--") + 1:]
    else:
        argv = sys.argv[1:] if AS_MODULE else []
    ap = argparse.ArgumentParser(prog="blender_bake.py")
    ap.add_argument("--scene", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--resolution", type=int, default=64)
    ap.add_argument("--bounces", type=int, default=4)
    ap.add_argument("--runs", default="64",
                    help="comma-separated bakes in order, SAMPLES or SAMPLES@SEED (seed default 1)")
    ap.add_argument("--sky", default=None, help="constant sky radiance R,G,B")
    ap.add_argument("--sun", default=None, help="X,Y,Z,E,DEG: a sun as Luxel's --sun (glTF axes)")
    ap.add_argument("--directional-radius", type=float, default=0.0,
                    help="angular radius of the glTF's directional lights, degrees (Luxel's option)")
    ap.add_argument("--materials", choices=["matched", "principled"], default="matched")
    ap.add_argument("--diffuse-weight", choices=["nv", "vh-average"], default="nv",
                    help="matched graph: the dielectric's diffuse weight 1 - F(0.04, n.wo) (default) "
                         "or 1 - (Appendix B's F(V.H) averaged over wi)")
    ap.add_argument("--uv-map", default=None, help="UV map name (default: the second one)")
    ap.add_argument("--denoise", choices=["none", "oidn"], default="none",
                    help="oidn: also write each bake denoised by Open Image Denoise "
                         "(blender_s<N>_seed<S>_oidn.exr; its seconds apart in blender.json)")
    ap.add_argument("--denoise-filter", choices=["RT", "RTLightmap"], default="RT",
                    help="OIDN filter: RT with hdr (the compositor's Denoise node; bpy 5.0.1's OIDN "
                         "has only its weights) or RTLightmap (needs LUXEL_OIDN_LIB, e.g. Luxel's)")
    ap.add_argument("--warmup", action="store_true",
                    help="one 1-spp bake before the runs, timed apart (first-bake costs)")
    ap.add_argument("--t0", type=float, default=None,
                    help="epoch seconds when the caller started blender (startup time)")
    return ap.parse_args(argv)


def first_of(names, available, what):
    """the first of names (newest Blender's spelling first) that exists"""
    for n in names:
        if n in available:
            return n
    raise SystemExit(f"Blender {bpy.app.version_string}: none of {names} among the {what}")


def principled_input(bsdf, names):
    """a Principled BSDF input by its name in this Blender version (4.0
    renamed "Emission" to "Emission Color")"""
    return bsdf.inputs[first_of(names, bsdf.inputs.keys(), "Principled BSDF inputs")]


def colour_space(names):
    """the first of names that is a colour space of this Blender version
    ("Linear" in 3.4, "Linear Rec.709" from 4.0)"""
    prop = bpy.types.ColorManagedInputColorspaceSettings.bl_rna.properties["name"]
    return first_of(names, [i.identifier for i in prop.enum_items], "colour spaces")


def import_gltf(path):
    """glTF import with lighting mode COMPAT ("Unitless"): the option is
    convert_lighting_mode up to 3.6, export_import_convert_lighting_mode from
    4.0 (io_scene_gltf2 shares it with the exporter)"""
    props = [p.identifier for p in bpy.ops.import_scene.gltf.get_rna_type().properties]
    opt = first_of(["export_import_convert_lighting_mode", "convert_lighting_mode"], props,
                   "glTF importer options")
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(path), **{opt: "COMPAT"})
    return opt


def mix_rgb(nt, blend):
    """a colour mix node of blend_type `blend`: (factor, A, B, result)
    sockets. ShaderNodeMix (3.4+; the float/vector/colour sockets share
    names, so they are taken by identifier) where it exists, else the legacy
    ShaderNodeMixRGB (Fac, Color1, Color2 -> Color). Same maths: factor
    clamped to [0, 1], result not clamped."""
    if hasattr(bpy.types, "ShaderNodeMix"):
        n = nt.nodes.new("ShaderNodeMix")
        n.data_type = "RGBA"
        n.blend_type = blend
        n.clamp_factor = True
        n.clamp_result = False
        ins = {s.identifier: s for s in n.inputs}
        outs = {s.identifier: s for s in n.outputs}
        return ins["Factor_Float"], ins["A_Color"], ins["B_Color"], outs["Result_Color"]
    n = nt.nodes.new("ShaderNodeMixRGB")
    n.blend_type = blend
    n.use_clamp = False
    return n.inputs["Fac"], n.inputs["Color1"], n.inputs["Color2"], n.outputs["Color"]


def socket_or_value(sock):
    """(output socket feeding `sock`, or None) and its default value"""
    if sock.is_linked:
        return sock.links[0].from_socket, None
    return None, sock.default_value


def feed(nt, src, dst):
    """connect src = (socket, value) into input socket dst"""
    sock, val = src
    if sock is not None:
        nt.links.new(sock, dst)
    else:
        dst.default_value = val


def is_rough_dielectric(bsdf):
    """Luxel's test (server/engine/bake/scene_data.cpp): metallic 0,
    roughness 1, no metallic-roughness texture; the importer links Metallic and
    Roughness to that texture when there is one"""
    m, r = bsdf.inputs["Metallic"], bsdf.inputs["Roughness"]
    return not (m.is_linked or r.is_linked) and m.default_value <= 0.0 and r.default_value >= 1.0


def schlick(nt, f0, c5):
    """Schlick F = f0 + (1 - f0) c5 = mix(f0, 1, c5) as a colour socket;
    f0 = (socket, value)"""
    fac, a, b, result = mix_rgb(nt, "MIX")
    nt.links.new(c5, fac)
    feed(nt, f0, a)
    b.default_value = (1.0, 1.0, 1.0, 1.0)
    return result


def multiscatter_ggx(nt, colour, rough):
    """Cycles' Glossy BSDF with the Multiscatter GGX distribution (Heitz et
    al. 2016, "Multiple-Scattering Microfacet BSDFs with the Smith Model": a
    random walk on the microsurface, energy conserving for a white colour).
    Its single-scattering term uses the height-correlated Smith G2 as Luxel
    does; alpha = roughness^2 as Luxel. The colour weights the first
    scattering and multiplies again at every further one (order k: colour^k),
    where Kulla & Conty 2017 (Luxel) use F_ms from the Schlick average F_avg."""
    glossy = nt.nodes.new("ShaderNodeBsdfGlossy")
    glossy.distribution = "MULTI_GGX"
    nt.links.new(colour, glossy.inputs["Color"])
    feed(nt, rough, glossy.inputs["Roughness"])
    return glossy.outputs["BSDF"]


def luxel_bsdf(nt, bsdf, specular, diffuse_weight):
    """Cycles nodes for Luxel's BSDF (kernels/shading/bsdf.h: glTF 2.0
    Appendix B.3 plus Kulla & Conty 2017 multiple-scattering compensation) of
    the glTF material behind the importer's Principled node; returns the
    shader socket.

    specular False (no material of the scene needs the GGX layer, so Luxel
    compiles it out): Lambert of the base colour.
    specular True, Appendix B's mix(dielectric, metal, metallic) as a Mix
    Shader by metallic, of
      metal      = Multiscatter GGX of colour F(base, n.wo),
      dielectric = Lambert of base (1 - Fd) + Multiscatter GGX of colour
                   F(0.04, n.wo),
    F Schlick. A node graph cannot see the microfacet normal, so F is taken
    at the shading normal (n.wo) where Appendix B takes it at V.H, for the
    glossy colour and for the diffuse weight alike. diffuse_weight "nv":
    Fd = F(0.04, n.wo), the same F as the glossy layer, so the dielectric's
    two layers sum to at most 1 like Luxel's (the closest directional
    albedo; README.md: where the two differ). "vh-average": Fd = the
    cosine-weighted mean over wi of Appendix B's F(0.04, V.H) for this wo,
    0.04 + 0.96 x 0.0285 (1 - n.wo)^2.6 (a fit, within 1e-3 of the
    quadrature), i.e. Appendix B's diffuse albedo, beside a glossy layer
    that is brighter than Appendix B's towards grazing."""
    base = socket_or_value(bsdf.inputs["Base Color"])
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Roughness"].default_value = 0.0  # Oren-Nayar sigma 0 = Lambert
    if not specular:
        feed(nt, base, diffuse.inputs["Color"])
        return diffuse.outputs["BSDF"]
    metal = socket_or_value(bsdf.inputs["Metallic"])
    rough = socket_or_value(bsdf.inputs["Roughness"])
    # c5 = (1 - clamp(n.wo))^5; Incoming points from the surface towards the
    # viewer, Normal is flipped to the viewer's side on back faces (as Luxel's frame)
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    dot = nt.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    nt.links.new(geo.outputs["Normal"], dot.inputs[0])
    nt.links.new(geo.outputs["Incoming"], dot.inputs[1])
    one_minus = nt.nodes.new("ShaderNodeMath")
    one_minus.operation = "SUBTRACT"
    one_minus.use_clamp = True
    one_minus.inputs[0].default_value = 1.0
    nt.links.new(dot.outputs["Value"], one_minus.inputs[1])
    c5 = nt.nodes.new("ShaderNodeMath")
    c5.operation = "POWER"
    nt.links.new(one_minus.outputs["Value"], c5.inputs[0])
    c5.inputs[1].default_value = 5.0
    f_metal = schlick(nt, base, c5.outputs["Value"])
    f_diel = schlick(nt, (None, (0.04, 0.04, 0.04, 1.0)), c5.outputs["Value"])
    # diffuse colour = base (1 - Fd)
    if diffuse_weight == "nv":
        fd = f_diel
    else:
        p = nt.nodes.new("ShaderNodeMath")
        p.operation = "POWER"
        nt.links.new(one_minus.outputs["Value"], p.inputs[0])
        p.inputs[1].default_value = 2.6
        fdv = nt.nodes.new("ShaderNodeMath")   # 0.04 + 0.96 x 0.0285 x (1 - mu)^2.6
        fdv.operation = "MULTIPLY_ADD"
        nt.links.new(p.outputs["Value"], fdv.inputs[0])
        fdv.inputs[1].default_value = 0.96 * 0.0285
        fdv.inputs[2].default_value = 0.04
        fd = fdv.outputs["Value"]
    inv = nt.nodes.new("ShaderNodeInvert")
    inv.inputs["Fac"].default_value = 1.0
    if diffuse_weight == "nv":
        nt.links.new(fd, inv.inputs["Color"])
    else:
        gray = nt.nodes.new("ShaderNodeCombineColor")
        for ch in ("Red", "Green", "Blue"):
            nt.links.new(fd, gray.inputs[ch])
        nt.links.new(gray.outputs["Color"], inv.inputs["Color"])
    fac, a, b, dcol = mix_rgb(nt, "MULTIPLY")
    fac.default_value = 1.0
    feed(nt, base, a)
    nt.links.new(inv.outputs["Color"], b)
    nt.links.new(dcol, diffuse.inputs["Color"])
    dielectric = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(diffuse.outputs["BSDF"], dielectric.inputs[0])
    nt.links.new(multiscatter_ggx(nt, f_diel, rough), dielectric.inputs[1])
    # mix(dielectric, metal, metallic): two glossy closures, not one of the
    # mixed colour, because the multiple scattering of each goes as its own
    # colour^k (Luxel mixes the two compensation lobes the same way)
    mix = nt.nodes.new("ShaderNodeMixShader")
    feed(nt, metal, mix.inputs["Fac"])
    nt.links.new(dielectric.outputs["Shader"], mix.inputs[1])
    nt.links.new(multiscatter_ggx(nt, f_metal, rough), mix.inputs[2])
    return mix.outputs["Shader"]


def convert_material(mat, mode, specular, diffuse_weight="nv"):
    """Material as Luxel shades it (mode 'matched') or the importer's
    Principled BSDF ('principled'), with one-sided emission, and a white
    Lambert receiver at the baked point."""
    nt = mat.node_tree
    bsdf = next((n for n in nt.nodes if n.type == "BSDF_PRINCIPLED"), None)
    out = next((n for n in nt.nodes if n.type == "OUTPUT_MATERIAL"), None)
    if bsdf is None or out is None:
        raise SystemExit(f"material {mat.name}: no Principled BSDF from the glTF importer")
    base = bsdf.inputs["Base Color"]
    emis = principled_input(bsdf, ["Emission Color", "Emission"])
    emis_strength = principled_input(bsdf, ["Emission Strength"])
    strength = float(emis_strength.default_value)
    info = {"base_color": "texture" if base.is_linked else [round(x, 6) for x in list(base.default_value)[:3]],
            "metallic": "texture" if bsdf.inputs["Metallic"].is_linked
            else round(bsdf.inputs["Metallic"].default_value, 6),
            "roughness": "texture" if bsdf.inputs["Roughness"].is_linked
            else round(bsdf.inputs["Roughness"].default_value, 6),
            "emission_color": [round(x, 6) for x in list(emis.default_value)[:3]],
            "emission_strength": strength,
            "double_sided": not mat.use_backface_culling}
    if emis.is_linked:
        raise SystemExit(f"material {mat.name}: emissive textures are not supported here")
    if mode == "matched":
        shader = luxel_bsdf(nt, bsdf, specular, diffuse_weight)
    else:
        # the importer's Principled BSDF without its emission (added below)
        emis_strength.default_value = 0.0
        shader = bsdf.outputs["BSDF"]
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
    # The baked point: Cycles starts bake paths with the camera-ray flag
    # (integrator/init_from_bake.h -> path_state_init_integrator), so "Is
    # Camera Ray" is 1 there only. A white Lambert there makes the DIFFUSE
    # pass without COLOR E/pi for every receiver (metals included); every
    # later vertex sees the material.
    lp = nt.nodes.new("ShaderNodeLightPath")
    white = nt.nodes.new("ShaderNodeBsdfDiffuse")
    white.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    white.inputs["Roughness"].default_value = 0.0
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(lp.outputs["Is Camera Ray"], mix.inputs["Fac"])
    nt.links.new(shader, mix.inputs[1])
    nt.links.new(white.outputs["BSDF"], mix.inputs[2])
    if mode == "matched":
        nt.nodes.remove(bsdf)
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return info


def gltf_json(path):
    """the glTF JSON of a .gltf or .glb file"""
    with open(path, "rb") as f:
        data = f.read()
    if data[:4] == b"glTF":
        n = int.from_bytes(data[12:16], "little")
        return json.loads(data[20:20 + n])
    return json.loads(data)


def world_axis(obj):
    """unit world direction of the object's local -Z (where a light points)"""
    import mathutils
    v = obj.matrix_world.to_3x3() @ mathutils.Vector((0.0, 0.0, -1.0))
    return v.normalized()


# Cycles' spot attenuation carries a cos(theta) factor in 3.4 and not in 5.0.1
# (kernel/light/spot.h: the smoothstep alone). Versions in between were not
# checked; 4.0 is where the spot light code was rewritten (spot.h's
# scaled_axis), so the switch is put there.
SPOT_HAS_COS = bpy.app.version < (4, 0, 0)


def spot_falloff_nodes(light, axis, inner, outer):
    """Cycles 3.4's spot (kernel/light/spot.h, spot_light_attenuation) is
    cos(theta) x smoothstep over its blend zone; with blend 0 it is
    cos(theta) inside the cone. 5.0.1's is the smoothstep alone: 1 inside
    the cone with blend 0. glTF's (and Luxel's, kernels/shading/lights.h)
    is the square of a linear ramp in cos theta from the outer to the inner
    cone. The light's Emission strength becomes ramp^2 / cos(theta) (3.4)
    or ramp^2 (5.0.1), with cos(theta) = |Incoming . axis| (Incoming: from
    the light towards the lit point in a light shader)."""
    light.use_nodes = True
    nt = light.node_tree
    em = next(n for n in nt.nodes if n.type == "EMISSION")
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    dot = nt.nodes.new("ShaderNodeVectorMath")
    dot.operation = "DOT_PRODUCT"
    nt.links.new(geo.outputs["Incoming"], dot.inputs[0])
    dot.inputs[1].default_value = tuple(axis)
    cd = nt.nodes.new("ShaderNodeMath")
    cd.operation = "ABSOLUTE"
    nt.links.new(dot.outputs["Value"], cd.inputs[0])
    ci, co = math.cos(inner), math.cos(outer)
    ramp = nt.nodes.new("ShaderNodeMath")      # clamp((cd - co) / (ci - co))
    ramp.operation = "MULTIPLY_ADD"
    ramp.use_clamp = True
    nt.links.new(cd.outputs["Value"], ramp.inputs[0])
    ramp.inputs[1].default_value = 1.0 / max(ci - co, 1e-4)
    ramp.inputs[2].default_value = -co / max(ci - co, 1e-4)
    sq = nt.nodes.new("ShaderNodeMath")
    sq.operation = "MULTIPLY"
    nt.links.new(ramp.outputs["Value"], sq.inputs[0])
    nt.links.new(ramp.outputs["Value"], sq.inputs[1])
    if not SPOT_HAS_COS:
        nt.links.new(sq.outputs["Value"], em.inputs["Strength"])
        return
    div = nt.nodes.new("ShaderNodeMath")
    div.operation = "DIVIDE"
    nt.links.new(sq.outputs["Value"], div.inputs[0])
    nt.links.new(cd.outputs["Value"], div.inputs[1])
    nt.links.new(div.outputs["Value"], em.inputs["Strength"])


def match_lights(scene, gltf, directional_radius_deg):
    """Check the importer's COMPAT conversion against the file and make each
    lamp what Luxel makes of the glTF light; returns a description."""
    defs = gltf.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    by_name = {}
    for i, d in enumerate(defs):
        by_name.setdefault(d.get("name", {"point": "Point", "spot": "Spot"}.get(d["type"], "Sun")), d)
    out = []
    for o in scene.objects:
        if o.type != "LIGHT":
            continue
        lt = o.data
        d = by_name.get(lt.name.split(".")[0]) or by_name.get(lt.name)
        if d is None:
            raise SystemExit(f"light {lt.name}: not found in the glTF's KHR_lights_punctual")
        inten = float(d.get("intensity", 1.0))
        want = inten if lt.type == "SUN" else 4.0 * math.pi * inten
        if abs(lt.energy - want) > 1e-5 * max(want, 1.0):
            raise SystemExit(f"light {lt.name}: importer gave energy {lt.energy}, expected {want}")
        axis = world_axis(o)
        rec = {"name": lt.name, "type": lt.type, "energy": lt.energy, "gltf_intensity": inten,
               "color": list(lt.color), "axis": [round(x, 6) for x in axis]}
        if lt.type == "SUN":
            lt.angle = 2.0 * math.radians(directional_radius_deg)   # angular diameter
            rec["angle_rad"] = lt.angle
        else:
            lt.shadow_soft_size = 0.0       # a point, like Luxel's (importer leaves 0.25 m)
            rec["position"] = list(o.matrix_world.translation)
        if lt.type == "SPOT":
            sp = d.get("spot", {})
            inner, outer = float(sp.get("innerConeAngle", 0.0)), float(sp.get("outerConeAngle", math.pi / 4))
            lt.spot_size = 2.0 * outer
            lt.spot_blend = 0.0
            spot_falloff_nodes(lt, axis, inner, outer)
            rec.update(inner=inner, outer=outer, spot_size=lt.spot_size,
                       strength="ramp^2 / cos" if SPOT_HAS_COS else "ramp^2")
        out.append(rec)
    return out


def add_sun(scene, spec):
    """--sun X,Y,Z,E,DEG: Luxel's --sun X,Y,Z --sun-illuminance E --sun-radius DEG"""
    import mathutils
    x, y, z, e, deg = (float(v) for v in spec.split(","))
    # glTF +Y up = Blender +Z up (the importer maps (x, y, z) to (x, -z, y))
    d = mathutils.Vector((x, -z, y)).normalized()
    lt = bpy.data.lights.new("luxel_sun", type="SUN")
    lt.energy = e
    lt.angle = 2.0 * math.radians(deg)
    ob = bpy.data.objects.new("luxel_sun", lt)
    ob.rotation_mode = "QUATERNION"
    ob.rotation_quaternion = d.to_track_quat("-Z", "Y")
    scene.collection.objects.link(ob)
    return {"name": "luxel_sun", "type": "SUN", "direction_blender": list(d), "energy": e, "angle_rad": lt.angle}


def exr_writer():
    """OpenImageIO's Python bindings where this Python has them (Debian's
    blender runs Debian's python3), else Blender's own image writer"""
    import importlib.util
    return "OpenImageIO" if importlib.util.find_spec("OpenImageIO") else "blender"


def baked_pixels(img, res):
    """the baked image as irradiance, (res, res, 4) float32, row 0 = top"""
    px = np.empty(res * res * 4, np.float32)
    img.pixels.foreach_get(px)
    # Blender stores rows bottom-up (row 0 = Blender v 0 = glTF v 1): flip so
    # row 0 is the top row = glTF TEXCOORD_1 v = 0, Luxel's convention.
    # Blender's diffuse pass without colour is E / pi: multiply RGB by pi.
    px = np.flipud(px.reshape(res, res, 4)).copy()
    px[..., :3] *= math.pi
    return px


def write_exr(path, px, res):
    if exr_writer() == "OpenImageIO":
        import OpenImageIO as oiio
        spec = oiio.ImageSpec(res, res, 4, "float")
        spec.attribute("compression", "zip")
        o = oiio.ImageOutput.create(path)
        if o is None or not o.open(path, spec):
            raise RuntimeError(oiio.geterror())
        o.write_image(px)
        o.close()
    else:  # Blender's own writer (it flips back to bottom-up in memory)
        tmp = bpy.data.images.new("out", res, res, alpha=True, float_buffer=True)
        # Non-Color, or the writer encodes the pixels with the sRGB curve
        # (0.5 -> 0.7354) in 3.4 and 5.0 alike, "Linear"/"Linear Rec.709"
        # images included: only Non-Color is written as is
        tmp.colorspace_settings.name = "Non-Color"
        tmp.pixels.foreach_set(np.flipud(px).ravel())
        tmp.filepath_raw = path
        tmp.file_format = "OPEN_EXR"
        tmp.save()
        bpy.data.images.remove(tmp)


def main():
    a = parse_args()
    os.makedirs(a.out, exist_ok=True)
    t_import0 = time.time()
    # the blender binary ran with --factory-startup; the bpy module loads the
    # user's startup file and preferences: this resets both to factory settings
    bpy.ops.wm.read_factory_settings(use_empty=True)
    lighting_option = import_gltf(a.scene)
    t_import = time.time() - t_import0

    t_setup0 = time.time()
    scene = bpy.context.scene
    meshes = [o for o in scene.objects if o.type == "MESH"]
    if not meshes:
        raise SystemExit("no meshes imported")
    n_objects = len(meshes)
    lights = match_lights(scene, gltf_json(a.scene), a.directional_radius)
    if a.sun:
        lights.append(add_sun(scene, a.sun))
    if len(meshes) > 1:
        # Blender's bake operator renders each selected object on its own, with
        # a full Cycles scene sync each time (1102 objects of the gas station:
        # 400 s for a 1-spp bake): join them into one object first, as users
        # baking one shared atlas do. UV maps join by name, materials are kept.
        bpy.ops.object.select_all(action="DESELECT")
        for o in meshes:
            o.select_set(True)
        bpy.context.view_layer.objects.active = meshes[0]
        bpy.ops.object.join()
        meshes = [o for o in scene.objects if o.type == "MESH"]
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
    triangles = 0
    for o in meshes:
        o.data.calc_loop_triangles()
        triangles += len(o.data.loop_triangles)

    img = bpy.data.images.new("lightmap", a.resolution, a.resolution, alpha=True, float_buffer=True)
    img.colorspace_settings.name = colour_space(["Linear Rec.709", "Linear"])
    materials = {}
    used = [m for m in bpy.data.materials if m.node_tree is not None and m.users > 0]
    specular = not all(is_rough_dielectric(next(n for n in m.node_tree.nodes
                                                  if n.type == "BSDF_PRINCIPLED")) for m in used)
    for m in used:
        materials[m.name] = convert_material(m, a.materials, specular, a.diffuse_weight)
        tex = m.node_tree.nodes.new("ShaderNodeTexImage")
        tex.image = img
        for n in m.node_tree.nodes:
            n.select = False
        tex.select = True
        m.node_tree.nodes.active = tex   # the bake target

    world = bpy.data.worlds.new("luxel_sky")
    scene.world = world
    if world.node_tree is None:   # 3.4; from 4.x (5.0: use_nodes deprecated) a new world has its nodes
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
    if hasattr(c, "use_guiding"):   # path guiding (3.4+): off, its default on CPU too
        c.use_guiding = False
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
    oidn = None
    if a.denoise == "oidn":   # the device is made before the timed bakes
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import oidn_lightmap
        oidn = oidn_lightmap.Oidn()
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
        px = baked_pixels(img, a.resolution)
        write_exr(os.path.join(a.out, name), px, a.resolution)
        bake = {"samples": spp, "seed": seed, "seconds": dt, "file": name}
        if oidn is not None:
            t = time.time()
            px[..., :3] = oidn.denoise(px[..., :3], a.denoise_filter)
            bake["denoise_s"] = time.time() - t
            bake["denoised_file"] = name.replace(".exr", "_oidn.exr")
            write_exr(os.path.join(a.out, bake["denoised_file"]), px, a.resolution)
        bakes.append(bake)
        print(f"blender_bake: {spp:6d} spp seed {seed}: {dt:8.3f} s", flush=True)

    info = {
        "blender_version": bpy.app.version_string,
        "scene": a.scene, "resolution": a.resolution, "bounces": a.bounces,
        "sky": sky, "materials": a.materials, "diffuse_weight": a.diffuse_weight, "uv_map": uv_name,
        "objects": len(meshes), "objects_joined": n_objects, "threads": scene.render.threads, "triangles": triangles,
        "as_module": AS_MODULE, "gltf_lighting_option": lighting_option,
        "bake_colour_space": img.colorspace_settings.name, "exr_writer": exr_writer(),
        # Cycles' defaults that differ between versions, left as they are
        "sampling_pattern": c.sampling_pattern,
        "use_light_tree": getattr(c, "use_light_tree", None),   # 3.6+, on by default
        "use_guiding": getattr(c, "use_guiding", None),
        "denoising": c.use_denoising, "adaptive_sampling": c.use_adaptive_sampling,
        "denoise": None if oidn is None else {"filter": a.denoise_filter, "library": oidn.path,
                                              "oidn_version": oidn.version, "device": "CPU",
                                              "inputs": "colour only"},
        # Blender (binary) or `import bpy` (module) start up to this script
        "startup_s": (T_STARTED - a.t0) if a.t0 else None,
        "import_s": t_import, "setup_s": t_setup, "warmup_s": warmup_s,
        "material_conversion": materials, "specular_layer": specular, "lights": lights,
        "bakes": bakes,
    }
    with open(os.path.join(a.out, "blender.json"), "w") as f:
        json.dump(info, f, indent=1)


main()
