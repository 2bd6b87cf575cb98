"""The Blender add-on (client/blender/luxel_blender) against a real luxeld on
loopback, in Blender 5.0.1's bpy module (headless; no mocks).

  <bpy venv>/bin/python tests/blender/blender_addon_test.py \\
      --luxel build/client/luxel --luxeld build/server/service/luxeld \\
      --work build/tests/blender/work [--screenshot lit_room.png]

The add-on is installed the way a user installs it (a link in a user
scripts folder's addons/) and enabled with addon_utils. Blender runs no
event loop here, so the tests advance a bake the way the add-on's timer
does: Session.step() every 0.1 s."""

import argparse
import math
import os
import pathlib
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

HERE = pathlib.Path(__file__).resolve().parent
ADDON_SRC = HERE.parents[1] / "client" / "blender" / "luxel_blender"
ARGS = None

# The user scripts folder must be set before bpy starts.
_SCRIPTS = tempfile.mkdtemp(prefix="luxel_bpy_scripts_")
os.makedirs(os.path.join(_SCRIPTS, "addons"))
os.symlink(ADDON_SRC, os.path.join(_SCRIPTS, "addons", "luxel_blender"))
os.environ["BLENDER_USER_SCRIPTS"] = _SCRIPTS

import bpy  # noqa: E402  (after BLENDER_USER_SCRIPTS)
import addon_utils  # noqa: E402  (importable once bpy has set up its paths)
import numpy as np  # noqa: E402

sys.path.insert(0, str(HERE))
import room_scene  # noqa: E402


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Daemon:
    """luxeld on 127.0.0.1:<free port>, ready once `luxel health` says SERVING."""

    def __init__(self, work, name="luxeld", extra=()):
        self.address = f"127.0.0.1:{free_port()}"
        self.data = work / f"{name}-data"
        shutil.rmtree(self.data, ignore_errors=True)
        self.log_path = work / f"{name}.log"
        self._log = open(self.log_path, "wb")
        self.proc = subprocess.Popen([ARGS.luxeld, "--listen", self.address, "--data-dir", str(self.data),
                                      *extra], stdout=self._log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 60
        while subprocess.run([ARGS.luxel, "health", "--server", self.address, "--timeout", "1"],
                             capture_output=True).returncode != 0:
            if self.proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError("luxeld did not start:\n" + self.log_path.read_text(errors="replace"))
            time.sleep(0.2)

    def status(self, bake_id):
        out = subprocess.run([ARGS.luxel, "status", bake_id, "--server", self.address, "--json"],
                             capture_output=True, text=True, check=True).stdout
        import json
        return json.loads(out.splitlines()[0])

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log.close()


def pixels(image):
    """(height, width, 4) float array, Blender's row order (bottom row first)."""
    w, h = image.size
    buf = np.empty(w * h * 4, dtype=np.float32)
    image.pixels.foreach_get(buf)
    return buf.reshape(h, w, 4)


class BlenderAddonTest(unittest.TestCase):
    daemon = None

    @classmethod
    def setUpClass(cls):
        cls.work = pathlib.Path(ARGS.work).resolve()
        cls.work.mkdir(parents=True, exist_ok=True)
        mod = addon_utils.enable("luxel_blender", default_set=True, handle_error=None)
        assert mod is not None, "the add-on did not enable"
        import luxel_blender
        cls.addon = luxel_blender
        cls.daemon = Daemon(cls.work)
        prefs = bpy.context.preferences.addons["luxel_blender"].preferences
        prefs.luxel_path = str(pathlib.Path(ARGS.luxel).resolve())
        prefs.mode = "SERVER"
        prefs.server = cls.daemon.address
        prefs.work_dir = str(cls.work / "bakes")

    @classmethod
    def tearDownClass(cls):
        if cls.daemon:
            cls.daemon.stop()
        addon_utils.disable("luxel_blender", default_set=True, handle_error=None)
        assert not hasattr(bpy.types.Scene, "luxel"), "unregister left scene.luxel behind"

    def setUp(self):
        room_scene.build_room()
        s = bpy.context.scene.luxel
        s.resolution, s.bounces, s.time_s = 64, 2, 0.0
        s.selection_only, s.baked_only = False, True
        s.snapshot_interval_s = 0.25
        # The room is closed: no sky reaches it, and a black one keeps the
        # bake independent of that claim. Snapshots come between iterations:
        # small batches make a bake of seconds send several.
        s.extra_args = "--sky 0,0,0 --paths-per-iteration 16384"

    def run_session(self, on_step=None, timeout=90.0):
        from luxel_blender import operators, session as sessions
        session = sessions.Session(operators.config_from_context(bpy.context))
        session.start(bpy.context)
        deadline = time.monotonic() + timeout
        while session.step():  # what the add-on's timer does
            if on_step:
                on_step(session)
            self.assertLess(time.monotonic(), deadline, f"bake still {session.phase}: {session.message}")
            time.sleep(0.1)
        return session

    # -------------------------------------------------------------- tests

    def test_1_bake_snapshots_apply_and_compare(self):
        from luxel_blender import apply as applier
        # Stopped by time, not samples: snapshots come at an interval of
        # seconds, so a sample target a fast machine (or a warm kernel cache)
        # reaches in one interval would leave a single snapshot.
        bpy.context.scene.luxel.samples = 1 << 20
        bpy.context.scene.luxel.time_s = 2.0
        seen = []  # image checksums, one per snapshot loaded
        status = []  # the status bar's text while the bake runs

        def watch(session):
            if session.progress.state == "RUNNING":
                status.append(session.status_text())
            if session.snapshots > len(seen):
                image = bpy.data.images[applier.LIGHTMAP_IMAGE]
                seen.append(float(np.nansum(pixels(image)[..., :3])))

        t0 = time.monotonic()
        session = self.run_session(watch)
        print(f"bake {session.bake_id}: {session.phase} in {time.monotonic() - t0:.1f} s, "
              f"{session.snapshots} snapshots loaded, sums {seen}", flush=True)
        self.assertEqual(session.phase, "DONE", session.error)
        self.assertGreaterEqual(len(seen), 2, "fewer than two snapshots reached the image")
        self.assertGreater(len(set(seen)), 1, "the snapshots did not change the image")
        self.assertTrue(status, "no progress while the bake ran")
        print(f"status bar: {status[-1]!r}", flush=True)
        self.assertRegex(status[-1], r"Luxel: +[\d.]+%  spp [\d.]+  error [\d.]+  ETA \S+")
        self.assertEqual(sorted(session.applied), sorted(room_scene.ALBEDO))
        self.assertEqual(os.listdir(session.snapshots_dir), [], "snapshot files left behind")

        image = bpy.data.images[applier.LIGHTMAP_IMAGE]
        # The denoised map when the daemon has OIDN (denoise = auto), else the raw one.
        self.assertTrue(image.filepath.endswith(os.path.basename(applier.lightmap_file(session.results_dir))))
        self.assertRegex(image.filepath, r"irradiance(_denoised)?\.exr$")
        px = pixels(image)[..., :3]
        self.assertTrue(np.isfinite(px).all())
        self.assertGreaterEqual(px.min(), 0.0)
        self.assertGreater(px.max(), 0.0)
        for name in room_scene.ALBEDO:
            obj = bpy.data.objects[name]
            self.assertIn(applier.LIGHTMAP_UV, obj.data.uv_layers, name)
            self.assertIn("UVMap", obj.data.uv_layers, name)  # the user's own set survives
            tree = obj.active_material.node_tree
            uv = tree.nodes["Luxel UV"]
            self.assertEqual(uv.uv_map, applier.LIGHTMAP_UV)
            tex = tree.nodes["Luxel Lightmap"]
            self.assertIs(tex.image, image)
            self.assertTrue(tex.inputs["Vector"].links[0].from_node == uv)
            out = next(n for n in tree.nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output)
            self.assertEqual(out.inputs["Surface"].links[0].from_node.name, "Luxel Mix")
        self.compare_emission_bake(session)
        self.render_screenshot()
        # Kept for test_5 (the re-bake below replaces the results).
        shutil.copytree(session.results_dir, self.work / "first_results", dirs_exist_ok=True)
        self.rebake_in_place(px)

    def rebake_in_place(self, first):
        """A second bake of the lightmapped scene: its LuxelLightmap layer goes
        out as TEXCOORD_1 and Luxel bakes that layout (no write-back), so the
        snapshots land in the image the materials already show, in place."""
        from luxel_blender import apply as applier
        bpy.context.scene.luxel.samples = 64
        session = self.run_session()
        self.assertEqual(session.phase, "DONE", session.error)
        self.assertFalse(any(f.endswith("_lightmapped.glb") for f in os.listdir(session.results_dir)),
                         "Luxel generated new UVs instead of baking the applied ones")
        self.assertEqual(sorted(session.applied), sorted(room_scene.ALBEDO))
        second = pixels(bpy.data.images[applier.LIGHTMAP_IMAGE])[..., :3]
        # Same layout, same light, fewer samples: the means over the atlas
        # agree to the noise of a 64-sample bake averaged over ~2700 texels.
        ratio = second.mean() / first.mean()
        print(f"re-bake in place: {session.snapshots} snapshots, mean ratio {ratio:.4f}", flush=True)
        self.assertLess(abs(ratio - 1.0), 0.05)

    def compare_emission_bake(self, session):
        """Cycles bakes each object's emission (the lightmap x base colour /
        pi the add-on wired) into an image in lightmap UV space, which must
        equal Luxel's irradiance x albedo / pi texel for texel. This is what
        breaks when the UV layer, the atlas scale/offset, the v flip, the
        image's colour space or the node wiring is wrong.

        Tolerance: 1e-4 relative (float32 rounding; measured at most 5e-6).
        For that the lightmap is read with Closest interpolation during this
        bake: Cycles samples each texel at its centre up to the rounding of
        the interpolated UVs (about 1e-3 texel), which with Linear filtering
        leaks a neighbour's value, and next to the box's contact shadow that
        moves a texel by up to 30 %. Closest returns the texel itself for any
        point inside it. The add-on's materials keep Linear."""
        from luxel_blender import apply as applier
        scene = bpy.context.scene
        scene.render.engine = "CYCLES"
        scene.cycles.device = "CPU"
        scene.cycles.samples = 1
        lightmap = bpy.data.images[applier.LIGHTMAP_IMAGE]
        irradiance = pixels(lightmap)
        size = lightmap.size[0]
        worst = []
        for name, albedo in room_scene.ALBEDO.items():
            if name == "Panel":
                continue  # emissive: its own emission is added, not the lightmap's alone
            obj = bpy.data.objects[name]
            target = bpy.data.images.new(f"emit_{name}", size, size, alpha=True, float_buffer=True)
            target.generated_color = (0, 0, 0, 0)
            tree = obj.active_material.node_tree
            tree.nodes["Luxel Lightmap"].interpolation = "Closest"
            node = tree.nodes.new("ShaderNodeTexImage")
            node.image = target
            tree.nodes.active = node
            bpy.ops.object.select_all(action="DESELECT")
            obj.select_set(True)
            bpy.context.view_layer.objects.active = obj
            bpy.ops.object.bake(type="EMIT", margin=0, use_clear=True, uv_layer=applier.LIGHTMAP_UV)
            got = pixels(target)
            tree.nodes.remove(node)
            tree.nodes["Luxel Lightmap"].interpolation = "Linear"
            # Texels this object's triangles cover in Blender's bake (the
            # bake clears to black; the room has no unlit texel) and that
            # Luxel covered fully (its alpha is coverage): partly covered
            # texels on chart borders are rasterized differently by the two.
            mask = (got[..., :3].sum(axis=2) > 0) & (irradiance[..., 3] > 0.999)
            expected = irradiance[..., :3] * np.float32(albedo) / np.float32(math.pi)
            diff = np.abs(got[..., :3] - expected)[mask]
            rel = diff / np.maximum(expected[mask], 1e-3)
            self.assertGreater(mask.sum(), 20, f"{name}: no texels in common")
            worst.append((name, int(mask.sum()), float(rel.max())))
            self.assertLess(rel.max(), 1e-4, f"{name}: emission bake != lightmap x albedo / pi")
        print("emission bake vs irradiance x albedo / pi (object, texels, max relative difference):",
              worst, flush=True)

    def render_screenshot(self):
        """A Cycles render of the room lit only by its lightmap."""
        scene = bpy.context.scene
        scene.render.engine = "CYCLES"
        scene.cycles.samples = 16
        scene.cycles.use_denoising = False
        scene.render.resolution_x, scene.render.resolution_y = 480, 360
        scene.render.resolution_percentage = 100
        scene.render.image_settings.file_format = "PNG"
        path = pathlib.Path(ARGS.screenshot or (self.work / "lit_room.png")).resolve()
        scene.render.filepath = str(path)
        bpy.ops.render.render(write_still=True)
        self.assertTrue(path.is_file())
        shot = bpy.data.images.load(str(path))
        px = pixels(shot)[..., :3]
        print(f"screenshot {path}: mean {px.mean():.3f}", flush=True)
        self.assertGreater(px.mean(), 0.05, "the render is black")

    def test_2_cancel(self):
        from luxel_blender import session as sessions
        bpy.context.scene.luxel.samples = 1 << 20  # hours at 64^2 on two cores
        state = {}

        def cancel_once_running(session):
            if session.progress.state == "RUNNING" and "t" not in state:
                state["t"] = time.monotonic()
                self.assertEqual(bpy.ops.luxel.cancel(), {"FINISHED"})

        session = self.run_session(cancel_once_running, timeout=60)
        self.assertIn("t", state, "the bake never ran")
        print(f"cancelled bake {session.bake_id} ended {time.monotonic() - state['t']:.2f} s "
              f"after the cancel: {session.message}", flush=True)
        self.assertEqual(session.phase, sessions.CANCELLED, session.message)
        self.assertEqual(session.final_state, "CANCELLED")
        info = self.daemon.status(session.bake_id)
        self.assertEqual(info["state"], "BAKE_STATE_CANCELLED")

    def test_4_local_bake(self):
        """`luxel bake --local`: progress parsed from its text output, the
        result applied the same way (no snapshots: the CLI writes none)."""
        from luxel_blender import session as sessions
        prefs = bpy.context.preferences.addons["luxel_blender"].preferences
        bpy.context.scene.luxel.samples = 64
        fractions = []
        prefs.mode = "LOCAL"
        try:
            session = self.run_session(lambda s: fractions.append(s.progress.fraction))
            print(f"local bake: {session.phase}, progress seen {sorted(set(fractions))[-3:]}", flush=True)
            self.assertEqual(session.phase, "DONE", session.error)
            self.assertEqual(sorted(session.applied), sorted(room_scene.ALBEDO))
            self.assertIn("Luxel Mix", bpy.data.objects["Floor"].active_material.node_tree.nodes)

            # Cancel: stopping the process is the cancel of an in-process bake.
            bpy.context.scene.luxel.samples = 1 << 20
            state = {}

            def cancel_once_running(session):
                if session.progress.state == "RUNNING" and "t" not in state:
                    state["t"] = time.monotonic()
                    session.cancel()

            session = self.run_session(cancel_once_running, timeout=60)
        finally:
            prefs.mode = "SERVER"
        self.assertIn("t", state, "the local bake never reported progress")
        self.assertEqual(session.phase, sessions.CANCELLED, session.message)

    def test_6_selection_and_shared_material(self):
        """Selected objects only: the others keep their meshes and materials;
        a material shared with an object outside the bake is copied for the
        baked one. Restore gives the original mesh back."""
        from luxel_blender import apply as applier
        box, panel, front = (bpy.data.objects[n] for n in ("Box", "Panel", "WallFront"))
        front.data.materials[0] = box.active_material  # shared with an object left out
        bpy.ops.object.select_all(action="DESELECT")
        box.select_set(True)
        panel.select_set(True)
        s = bpy.context.scene.luxel
        s.selection_only, s.samples = True, 32
        bpy.ops.object.select_all(action="DESELECT")
        with self.assertRaisesRegex(RuntimeError, "no mesh object is selected"):
            bpy.ops.luxel.bake(wait=True)
        box.select_set(True)
        panel.select_set(True)
        session = self.run_session()
        self.assertEqual(session.phase, "DONE", session.error)
        self.assertEqual(sorted(session.applied), ["Box", "Panel"])
        self.assertEqual(box.active_material.name, "Box (Luxel)")
        self.assertIn("Luxel Mix", box.active_material.node_tree.nodes)
        self.assertEqual(front.active_material.name, "Box")
        self.assertNotIn("Luxel Mix", front.active_material.node_tree.nodes)
        self.assertNotIn(applier.LIGHTMAP_UV, bpy.data.objects["Floor"].data.uv_layers)
        bpy.ops.object.select_all(action="DESELECT")
        box.select_set(True)
        self.assertEqual(bpy.ops.luxel.restore_meshes(), {"FINISHED"})
        self.assertEqual(box.data.name, "Box")
        self.assertNotIn(applier.ORIGINAL_MESH_PROP, box)
        self.assertNotIn(applier.LIGHTMAP_UV, box.data.uv_layers)

    def test_7_token_file(self):
        """A daemon with a bearer token: the token file in the preferences
        reaches luxel (in its environment); a wrong one fails naming the
        daemon and UNAUTHENTICATED."""
        token = self.work / "token"
        token.write_text("s3cret-blender-token\n")
        token.chmod(0o600)  # luxeld refuses a token file others can read
        daemon = Daemon(self.work, "luxeld-token", ["--token-file", str(token)])
        prefs = bpy.context.preferences.addons["luxel_blender"].preferences
        saved = prefs.server, prefs.token_file
        bpy.context.scene.luxel.samples = 16
        try:
            prefs.server, prefs.token_file = daemon.address, str(token)
            session = self.run_session()
            self.assertEqual(session.phase, "DONE", f"{session.message} / {session.error}")
            wrong = self.work / "wrong_token"
            wrong.write_text("not-the-token\n")
            prefs.token_file = str(wrong)
            session = self.run_session()
            print(f"wrong token: {session.error}", flush=True)
            self.assertEqual(session.phase, "FAILED")
            self.assertIn(daemon.address, session.error)
            self.assertIn("UNAUTHENTICATED", session.error)
        finally:
            prefs.server, prefs.token_file = saved
            daemon.stop()

    def test_5_lightmap_texcoord_extra(self):
        """A write-back that keeps the user's sets and puts the lightmap in
        TEXCOORD_2, named by each primitive's extras.lightmapTexCoord, gives
        the same LuxelLightmap layer as the same UVs in TEXCOORD_1. Made from
        test_1's write-back by moving its sets; no daemon."""
        import json
        import struct
        from luxel_blender import apply as applier
        results = self.work / "first_results"
        glb = next(results.glob("*_lightmapped.glb"), None)
        if glb is None:
            self.skipTest("test_1 left no write-back")

        def layers():
            return {name: np.array([tuple(d.uv) for d in bpy.data.objects[name].data.uv_layers[
                applier.LIGHTMAP_UV].data]) for name in room_scene.ALBEDO}

        applier.apply_uvs(str(results), str(glb))
        expected = layers()
        data = glb.read_bytes()
        length = struct.unpack_from("<I", data, 12)[0]
        doc = json.loads(data[20:20 + length])
        for mesh in doc["meshes"]:
            for prim in mesh["primitives"]:
                attrs = prim["attributes"]
                attrs["TEXCOORD_2"], attrs["TEXCOORD_1"] = attrs["TEXCOORD_1"], attrs["TEXCOORD_0"]
                prim.setdefault("extras", {})["lightmapTexCoord"] = 2
        text = json.dumps(doc).encode()
        text += b" " * (-len(text) % 4)
        rest = data[20 + length:]
        moved = self.work / "moved_lightmapped.glb"
        moved.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + len(rest))
                          + struct.pack("<II", len(text), 0x4E4F534A) + text + rest)
        objects, _ = applier.apply_uvs(str(results), str(moved))
        self.assertEqual(len(objects), len(room_scene.ALBEDO))
        floor = bpy.data.objects["Floor"].data
        self.assertEqual([l.name for l in floor.uv_layers], ["UVMap", "UVMap.001", applier.LIGHTMAP_UV])
        got = layers()
        for name in room_scene.ALBEDO:
            np.testing.assert_array_equal(got[name], expected[name], err_msg=name)

    def test_8_installs_as_extension(self):
        """The zipped folder installs from disk as a Blender extension (its
        blender_manifest.toml) and registers, with preferences under the
        extension's module name. A fresh Blender: user resources in a
        temporary folder, so nothing of the user's is touched."""
        import zipfile
        archive = self.work / "luxel_blender.zip"
        with zipfile.ZipFile(archive, "w") as z:
            for f in sorted(ADDON_SRC.rglob("*")):
                if f.is_file() and "__pycache__" not in f.parts:
                    z.write(f, pathlib.Path("luxel_blender") / f.relative_to(ADDON_SRC))
        script = (
            "import bpy\n"
            f"r = bpy.ops.extensions.package_install_files(filepath={str(archive)!r}, "
            "repo='user_default', enable_on_install=True)\n"
            "mods = [a.module for a in bpy.context.preferences.addons if a.module.endswith('luxel_blender')]\n"
            "prefs = bpy.context.preferences.addons[mods[0]].preferences\n"
            "print('EXT', r, mods, prefs.server, hasattr(bpy.types.Scene, 'luxel'))\n")
        with tempfile.TemporaryDirectory() as home:
            env = dict(os.environ, BLENDER_USER_RESOURCES=home)
            env.pop("BLENDER_USER_SCRIPTS", None)
            out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                                 text=True, timeout=120)
        line = next((l for l in out.stdout.splitlines() if l.startswith("EXT")), out.stdout + out.stderr)
        print(line, flush=True)
        self.assertIn("{'FINISHED'} ['bl_ext.user_default.luxel_blender'] 127.0.0.1:50051 True", line)

    def test_3_unreachable_daemon(self):
        prefs = bpy.context.preferences.addons["luxel_blender"].preferences
        dead = f"127.0.0.1:{free_port()}"  # nothing listens there
        saved, prefs.server = prefs.server, dead
        try:
            t0 = time.monotonic()
            with self.assertRaises(RuntimeError) as caught:
                bpy.ops.luxel.bake(wait=True)
            elapsed = time.monotonic() - t0
        finally:
            prefs.server = saved
        message = str(caught.exception)
        print(f"unreachable daemon, after {elapsed:.2f} s: {message.strip()}", flush=True)
        self.assertIn(dead, message)
        self.assertIn("cannot reach luxeld", message)

        # A port that accepts connections and never answers (a hung host, a
        # wrong service): the health check's deadline ends it, no hang (a
        # hang would end in ctest's timeout; the time is printed, not
        # asserted).
        with socket.socket() as silent:
            silent.bind(("127.0.0.1", 0))
            silent.listen(8)
            address = f"127.0.0.1:{silent.getsockname()[1]}"
            prefs.server = address
            try:
                t0 = time.monotonic()
                with self.assertRaises(RuntimeError) as caught:
                    bpy.ops.luxel.bake(wait=True)
                elapsed = time.monotonic() - t0
            finally:
                prefs.server = saved
        message = str(caught.exception)
        print(f"silent daemon, after {elapsed:.2f} s: {message.strip()}", flush=True)
        self.assertIn(address, message)


def main():
    global ARGS
    parser = argparse.ArgumentParser()
    parser.add_argument("--luxel", required=True)
    parser.add_argument("--luxeld", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--screenshot", default="")
    ARGS, rest = parser.parse_known_args()
    try:
        result = unittest.main(argv=[sys.argv[0], "-v", *rest], exit=False).result
    finally:
        shutil.rmtree(_SCRIPTS, ignore_errors=True)
    sys.exit(0 if result.wasSuccessful() else 1)


if __name__ == "__main__":
    main()
