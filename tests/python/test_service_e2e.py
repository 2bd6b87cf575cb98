"""End-to-end through the Python client against a real luxeld on loopback.

Needs LUXELD (path of the daemon binary) and the generated stubs on the path;
CMake's ctest entry python_client_e2e sets both. By hand:

    LUXELD=build/server/service/luxeld LUXEL_CACHE_DIR=build/cl-cache \
    PYTHONPATH=client/python:build/python /usr/bin/python3 -m unittest -v tests/python/test_service_e2e.py
"""

import hashlib
import json
import os
import pathlib
import shutil
import subprocess
import tempfile
import threading
import time
import unittest

from luxel_client import Client, LuxelError, luxel_pb2, scene_id, state_name
from luxeld_process import Luxeld, free_loopback_port

SCENES = pathlib.Path(os.environ.get("LUXEL_SCENES_DIR",
                                     pathlib.Path(__file__).resolve().parents[2] / "scenes"))
CORNELL = SCENES / "cornell_box.gltf"
FOLIAGE = SCENES / "foliage_instanced.glb"
# Small bakes (a few hundredths of a second on PoCL), batches of the minimum
# size so a bake runs several iterations.
SMALL = dict(resolution=32, samples_per_texel=16, paths_per_iteration=1024, snapshot_interval_s=0.05,
             snapshot_max_side=64)
# The watched bakes must outlast the daemon's shortest snapshot interval
# (0.05 s) on any machine, so they stop on time rather than on samples.
TIMED = dict(SMALL, samples_per_texel=0, time_budget_s=0.5)
EXPECTED_ARTIFACTS = {"irradiance.exr", "preview.png", "manifest.json"}
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
EXR_MAGIC = b"\x76\x2f\x31\x01"


def sha256_of(path):
    return hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()


def expected_scene_id(main_bytes, resources):
    """The scene id rule of luxel.proto, computed here independently of the
    client: ``resources`` maps each uri (as written) to its bytes."""
    main = hashlib.sha256(main_bytes).hexdigest()
    if not resources:
        return main
    manifest = f"luxel-scene-v1\n{main}\n".encode()
    for uri in sorted(resources, key=lambda u: u.encode()):
        data = resources[uri]
        manifest += f"{uri}\t{len(data)}\t{hashlib.sha256(data).hexdigest()}\n".encode()
    return hashlib.sha256(manifest).hexdigest()


def collect(client, bake_id):
    """All events of one WatchBake stream, to its end."""
    with client.watch_bake(bake_id) as watch:
        return list(watch)


class ServiceEndToEndTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        binary = os.environ.get("LUXELD")
        if not binary or not os.access(binary, os.X_OK):
            raise unittest.SkipTest("LUXELD does not name the luxeld binary")
        cls.daemon = Luxeld(binary, ["--max-concurrent-bakes", "2"])
        try:
            cls.daemon.start()
        except Exception:
            cls.daemon.cleanup()
            raise
        cls.client = Client(cls.daemon.address, timeout=120)
        cls.out = tempfile.TemporaryDirectory(prefix="luxel_py_out_")

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        status = cls.daemon.stop()
        log = cls.daemon.log()
        cls.daemon.cleanup()
        cls.out.cleanup()
        if status != 0:
            raise AssertionError(f"luxeld exited {status} after SIGTERM (expected 0); its log:\n{log}")

    # ---------------------------------------------------------------- helpers

    def out_dir(self, name):
        path = pathlib.Path(self.out.name) / name
        path.mkdir(parents=True, exist_ok=True)
        return path

    def check_events(self, events, bake_id):
        """The WatchBake contract: the first event is the current state, the
        stream ends with exactly one final event of a finished bake."""
        self.assertTrue(events, "the stream carried no event")
        self.assertEqual(events[0].info.bake_id, bake_id)
        self.assertNotEqual(events[0].info.state, luxel_pb2.BAKE_STATE_UNSPECIFIED)
        self.assertTrue(events[-1].final, "the stream ended without a final event")
        self.assertEqual(sum(e.final for e in events), 1)
        self.assertEqual(state_name(events[-1].info.state), "SUCCEEDED", events[-1].info.error_message)
        spp = [e.info.progress.mean_spp for e in events]
        self.assertEqual(spp, sorted(spp), "progress went backwards")

    def check_snapshot(self, snapshot):
        self.assertIn(snapshot.format, (luxel_pb2.SNAPSHOT_FORMAT_PNG, luxel_pb2.SNAPSHOT_FORMAT_UNSPECIFIED))
        self.assertTrue(snapshot.data.startswith(PNG_MAGIC), "snapshot is not a PNG")
        self.assertGreater(snapshot.width, 0)
        self.assertGreater(snapshot.height, 0)
        self.assertLessEqual(max(snapshot.width, snapshot.height), 64)

    def download_all(self, client, info, folder):
        """Downloads every artifact (the client checks size and the daemon's
        sha256) and re-hashes the files on disk independently."""
        self.assertTrue(EXPECTED_ARTIFACTS <= set(info.artifacts), list(info.artifacts))
        for artifact in info.artifacts:
            got = client.download(info.bake_id, artifact, folder / artifact)
            self.assertEqual(got.sha256, sha256_of(got.path), artifact)
            self.assertEqual(got.size, got.path.stat().st_size)
            self.assertGreater(got.size, 0, artifact)
        self.assertTrue((folder / "preview.png").read_bytes().startswith(PNG_MAGIC))
        self.assertTrue((folder / "irradiance.exr").read_bytes().startswith(EXR_MAGIC))
        json.loads((folder / "manifest.json").read_text())
        self.assertEqual([p.name for p in folder.iterdir() if p.name.endswith(".part")], [])

    def bake_and_verify(self, scene_path, name):
        scene = self.client.upload_scene(scene_path)
        resources = {}
        if scene_path.suffix == ".gltf":
            gltf = json.loads(scene_path.read_text())
            resources = {b["uri"]: (scene_path.parent / b["uri"]).read_bytes() for b in gltf["buffers"]}
        self.assertEqual(scene.scene_id, expected_scene_id(scene_path.read_bytes(), resources))
        self.assertEqual(scene_id(scene_path), scene.scene_id)
        self.assertGreater(scene.statistics.triangles, 0)
        info = self.client.submit_bake(scene.scene_id, **TIMED)
        self.assertEqual(info.scene_id, scene.scene_id)
        events = collect(self.client, info.bake_id)
        self.check_events(events, info.bake_id)
        snapshots = [e.snapshot for e in events if e.HasField("snapshot") and e.snapshot.data]
        self.assertTrue(snapshots, f"no snapshot in {len(events)} events")
        for snapshot in snapshots:
            self.check_snapshot(snapshot)
        spp = [s.progress.mean_spp for s in snapshots]
        self.assertEqual(spp, sorted(spp), "snapshots out of order")
        final = self.client.get_bake(info.bake_id)
        self.assertEqual(state_name(final.state), "SUCCEEDED")
        self.assertEqual(final.termination, "time")
        self.assertGreaterEqual(final.progress.elapsed_s, TIMED["time_budget_s"])
        self.assertGreater(final.progress.mean_spp, 0)
        self.download_all(self.client, final, self.out_dir(name))
        return scene, final

    # ---------------------------------------------------------------- tests

    def test_gltf_with_external_buffer_end_to_end(self):
        scene, info = self.bake_and_verify(CORNELL, "cornell")
        self.assertEqual(scene.size, CORNELL.stat().st_size + (SCENES / "cornell_box.bin").stat().st_size)
        self.assertEqual(scene.statistics.triangles, 32)
        self.assertIn(scene.scene_id, [s.scene_id for s in self.client.list_scenes()])
        self.assertEqual(self.client.get_scene(scene.scene_id).scene_id, scene.scene_id)
        self.assertTrue(self.client.upload_scene(CORNELL).already_stored)
        succeeded = self.client.list_bakes(states=["SUCCEEDED"])
        self.assertIn(info.bake_id, [b.bake_id for b in succeeded])
        self.assertTrue(all(b.state == luxel_pb2.BAKE_STATE_SUCCEEDED for b in succeeded))
        # A late watcher sees the finished state at once, then the stream ends.
        late = collect(self.client, info.bake_id)
        self.assertTrue(late[0].final or late[-1].final)
        self.assertEqual(state_name(late[-1].info.state), "SUCCEEDED")

    def test_glb_end_to_end(self):
        scene, _ = self.bake_and_verify(FOLIAGE, "foliage")
        self.assertEqual(scene.format, luxel_pb2.SCENE_FORMAT_GLB)

    def test_idempotency_key_returns_the_same_job(self):
        scene = self.client.upload_scene(CORNELL)
        first = self.client.submit_bake(scene.scene_id, idempotency_key="py-e2e-key", **SMALL)
        again = self.client.submit_bake(scene.scene_id, idempotency_key="py-e2e-key", **SMALL)
        self.assertEqual(first.bake_id, again.bake_id)
        self.assertEqual(state_name(self.client.wait(first.bake_id).state), "SUCCEEDED")

    def test_unknown_ids_are_not_found(self):
        unknown = "0123456789abcdef0123456789abcdef"
        calls = {
            "GetBake": lambda: self.client.get_bake(unknown),
            "CancelBake": lambda: self.client.cancel_bake(unknown),
            "WatchBake": lambda: collect(self.client, unknown),
            "DownloadResult": lambda: self.client.download(unknown, "preview.png", self.out_dir("nf")),
            "GetScene": lambda: self.client.get_scene("ab" * 32),
            "DeleteScene": lambda: self.client.delete_scene("ab" * 32),
            "SubmitBake": lambda: self.client.submit_bake("ab" * 32, **SMALL),
        }
        for rpc, call in calls.items():
            with self.subTest(rpc=rpc), self.assertRaises(LuxelError) as caught:
                call()
            self.assertEqual(caught.exception.code, "NOT_FOUND", f"{rpc}: {caught.exception}")
            self.assertFalse(caught.exception.local)
        self.assertEqual(list(self.out_dir("nf").iterdir()), [], "a failed download left a file")

    def test_wrong_hash_or_short_stream_is_data_loss_and_stores_nothing(self):
        # Unique bytes, so no other test can have stored this content.
        data = CORNELL.read_bytes() + b"\n" * 7
        bin_bytes = (SCENES / "cornell_box.bin").read_bytes()
        true_id = expected_scene_id(data, {"cornell_box.bin": bin_bytes})
        resource = luxel_pb2.ResourceHeader(uri="cornell_box.bin", size=len(bin_bytes),
                                            sha256=hashlib.sha256(bin_bytes).hexdigest())

        def header(**overrides):
            fields = dict(name="bad.gltf", format=luxel_pb2.SCENE_FORMAT_GLTF, total_size=len(data),
                          sha256=hashlib.sha256(data).hexdigest(), resources=[resource])
            fields.update(overrides)
            return luxel_pb2.SceneUploadHeader(**fields)

        bad_resource = luxel_pb2.ResourceHeader(uri="cornell_box.bin", size=len(bin_bytes), sha256="0" * 64)
        cases = {
            "wrong main hash": (header(sha256="f" * 64), [data, bin_bytes]),
            "wrong resource hash": (header(resources=[bad_resource]), [data, bin_bytes]),
            "truncated stream": (header(), [data, bin_bytes[:100]]),
        }
        for case, (head, chunks) in cases.items():
            with self.subTest(case=case), self.assertRaises(LuxelError) as caught:
                self.client._upload(head, iter(chunks))
            self.assertEqual(caught.exception.code, "DATA_LOSS", f"{case}: {caught.exception}")
        stored = [s.scene_id for s in self.client.list_scenes()]
        self.assertNotIn(true_id, stored)
        self.assertNotIn("f" * 64, stored)
        with self.assertRaises(LuxelError) as caught:
            self.client.get_scene(true_id)
        self.assertEqual(caught.exception.code, "NOT_FOUND")

    def test_invalid_settings_name_the_field(self):
        scene = self.client.upload_scene(CORNELL)
        before = len(self.client.list_bakes())
        cases = [({"max_bounces": 99}, "max_bounces"),
                 ({"resolution": 1_000_000}, "resolution"),
                 ({"samples_per_texel": 0}, "samples_per_texel"),
                 ({"paths_per_iteration": 7}, "paths_per_iteration"),
                 ({"time_budget_s": -1.0}, "time_budget_s"),
                 ({"encodings": ["sh2", "sh2"]}, "settings.encodings: 'sh2' is listed twice"),
                 ({"sun": {"illuminance": 1.0, "angular_radius_degrees": 95.0}},
                  "settings.sun.angular_radius_degrees: must be in [0, 90), got 95")]
        for overrides, field in cases:
            settings = dict(SMALL, **overrides)
            with self.subTest(field=field), self.assertRaises(LuxelError) as caught:
                self.client.submit_bake(scene.scene_id, **settings)
            self.assertEqual(caught.exception.code, "INVALID_ARGUMENT", str(caught.exception))
            self.assertIn(field, caught.exception.message)
            self.assertFalse(caught.exception.local, "the daemon, not the client, should refuse it")
        # The same words as `luxel bake --bounces 99` (tests/cli) and the schema's unit tests.
        with self.assertRaises(LuxelError) as caught:
            self.client.submit_bake(scene.scene_id, **dict(SMALL, max_bounces=99))
        self.assertEqual(caught.exception.message, "settings.max_bounces: must be in [0, 64], got 99")
        self.assertEqual(len(self.client.list_bakes()), before, "an invalid bake was queued")

    def test_concurrent_clients_with_two_watchers_each(self):
        scenes = [CORNELL, FOLIAGE, CORNELL]
        errors, results = [], {}
        lock = threading.Lock()

        def watcher(bake_id, slot):
            try:
                with Client(self.daemon.address) as own:
                    events = collect(own, bake_id)
                with lock:
                    results.setdefault(bake_id, []).append(events)
            except Exception as e:  # reported by the main thread
                errors.append(f"watcher {slot} of {bake_id}: {e!r}")

        def submitter(index):
            try:
                with Client(self.daemon.address, timeout=120) as own:
                    scene = own.upload_scene(scenes[index])
                    info = own.submit_bake(scene.scene_id, seed=index + 1, **SMALL)
                    watchers = [threading.Thread(target=watcher, args=(info.bake_id, w)) for w in range(2)]
                    for t in watchers:
                        t.start()
                    for t in watchers:
                        t.join(timeout=240)
                    final = own.get_bake(info.bake_id)
                    self.assertEqual(state_name(final.state), "SUCCEEDED")
                    self.assertEqual(final.termination, "samples")
                    self.assertGreaterEqual(final.progress.mean_spp, SMALL["samples_per_texel"])
                    self.download_all(own, final, self.out_dir(f"concurrent_{index}"))
            except Exception as e:
                errors.append(f"client {index}: {e!r}")

        threads = [threading.Thread(target=submitter, args=(i,)) for i in range(len(scenes))]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=300)
        self.assertEqual(errors, [])
        self.assertEqual(len(results), 3)
        for bake_id, streams in results.items():
            self.assertEqual(len(streams), 2)
            for events in streams:
                self.check_events(events, bake_id)

    def test_watcher_that_disconnects_does_not_disturb_the_bake(self):
        scene = self.client.upload_scene(CORNELL)
        info = self.client.submit_bake(scene.scene_id, **TIMED)
        with Client(self.daemon.address) as quitter:
            watch = quitter.watch_bake(info.bake_id)
            first, second = next(watch), next(watch)
            self.assertEqual(first.info.bake_id, info.bake_id)
            self.assertFalse(second.final, "the bake ended before the watcher could leave mid-stream")
            watch.cancel()
            self.assertEqual(list(watch), [], "events after cancel()")
        events = collect(self.client, info.bake_id)
        self.check_events(events, info.bake_id)
        self.download_all(self.client, events[-1].info, self.out_dir("after_disconnect"))
        # The daemon forgets the closed stream (ServerStatus.watchers counts open ones).
        deadline = time.monotonic() + 10
        while self.client.server_status().watchers > 0 and time.monotonic() < deadline:
            time.sleep(0.1)
        self.assertEqual(self.client.server_status().watchers, 0)

    def test_slow_watcher_gets_the_newest_event_not_a_backlog(self):
        # gRPC's transport buffers what the daemon has sent, so a reader slower
        # than the snapshot rate would work through a backlog; latest_only
        # drains the stream and hands over only the newest event.
        scene = self.client.upload_scene(CORNELL)
        info = self.client.submit_bake(scene.scene_id, **dict(TIMED, time_budget_s=1.5))
        received = []
        with self.client.watch_bake(info.bake_id, latest_only=True) as watch:
            for event in watch:
                received.append((time.time(), event))
                if not event.final:
                    time.sleep(0.6)  # a slow editor redraw
        self.assertTrue(received and received[-1][1].final, "no final event")
        final_at, final = received[-1]
        self.assertEqual(state_name(final.info.state), "SUCCEEDED")
        # About one event per 0.6 s read, not one per 0.05 s snapshot, and the
        # final event arrives within one read of the bake's end.
        self.assertLessEqual(len(received), 8, f"{len(received)} events: a backlog was replayed")
        self.assertLess(final_at - final.info.finished_at, 1.5)
        for _, event in received:
            self.assertEqual(event.info.bake_id, info.bake_id)

    def test_cancel_and_scene_in_use(self):
        # A private copy of the scene (unique bytes) so deleting it touches no other test.
        folder = self.out_dir("private_scene")
        shutil.copy(SCENES / "cornell_box.bin", folder)
        (folder / "cornell.gltf").write_bytes(CORNELL.read_bytes() + b"\n\n")
        scene = self.client.upload_scene(folder / "cornell.gltf")
        info = self.client.submit_bake(scene.scene_id, resolution=32, samples_per_texel=1_000_000,
                                       time_budget_s=60, paths_per_iteration=1024)
        with self.assertRaises(LuxelError) as caught:
            self.client.delete_scene(scene.scene_id)
        self.assertEqual(caught.exception.code, "FAILED_PRECONDITION")
        self.client.cancel_bake(info.bake_id)
        final = self.client.wait(info.bake_id)
        self.assertEqual(state_name(final.state), "CANCELLED")
        self.client.delete_scene(scene.scene_id)
        self.assertNotIn(scene.scene_id, [s.scene_id for s in self.client.list_scenes()])


class TokenTest(unittest.TestCase):
    """With a token (LUXELD_TOKEN or --token-file), calls without the bearer
    token (or with a wrong one) get UNAUTHENTICATED; the client's token=
    sends it."""

    def test_bearer_token(self):
        binary = os.environ.get("LUXELD")
        if not binary or not os.access(binary, os.X_OK):
            self.skipTest("LUXELD does not name the luxeld binary")
        daemon = Luxeld(binary, env={"LUXELD_TOKEN": "py-e2e-secret"})
        try:
            daemon.start()
            for token in (None, "wrong"):
                with Client(daemon.address, token=token) as client, self.assertRaises(LuxelError) as caught:
                    client.list_scenes()
                self.assertEqual(caught.exception.code, "UNAUTHENTICATED", str(token))
            with Client(daemon.address, token="py-e2e-secret") as client:
                scene = client.upload_scene(FOLIAGE)
                self.assertEqual([s.scene_id for s in client.list_scenes()], [scene.scene_id])
            self.assertEqual(daemon.stop(), 0, daemon.log())
        finally:
            daemon.cleanup()


class FinishTest(unittest.TestCase):
    """CancelBake with finish keeps the bake: a running one ends after its
    current iteration with what it traced (SUCCEEDED, termination "stopped",
    results downloadable); a queued one finishes as soon as it starts, and
    the request survives a kill -9 of the daemon."""

    def test_finish_running_and_queued_bakes(self):
        binary = os.environ.get("LUXELD")
        if not binary or not os.access(binary, os.X_OK):
            self.skipTest("LUXELD does not name the luxeld binary")
        args = ["--max-concurrent-bakes", "1", "--checkpoint-interval", "0.3"]
        daemon = Luxeld(binary, args).start()
        self.addCleanup(daemon.cleanup)
        replaced = []
        self.addCleanup(lambda: [d.cleanup() for d in replaced])
        out = tempfile.TemporaryDirectory(prefix="luxel_finish_")
        self.addCleanup(out.cleanup)
        long_bake = dict(resolution=32, samples_per_texel=0, time_budget_s=600,
                         paths_per_iteration=4096)
        with Client(daemon.address) as c:
            scene = c.upload_scene(CORNELL)
            running = c.submit_bake(scene.scene_id, **long_bake)
            queued = c.submit_bake(scene.scene_id, seed=2, **long_bake)
            deadline = time.monotonic() + 60
            while c.get_bake(running.bake_id).progress.paths == 0:
                self.assertLess(time.monotonic(), deadline)
                time.sleep(0.05)
            asked = c.cancel_bake(queued.bake_id, finish=True)
            self.assertEqual(state_name(asked.state), "QUEUED")
            self.assertTrue(asked.finish_requested)
            time.sleep(0.5)  # a checkpoint of the running bake
        daemon.process.kill()
        daemon.process.wait()
        replaced.append(daemon)
        daemon = Luxeld(binary, args, data_dir=daemon.data_dir).start(address=daemon.address)
        replaced.append(daemon)
        with Client(daemon.address) as c:
            deadline = time.monotonic() + 60
            while c.get_bake(running.bake_id).progress.paths == 0 or \
                    state_name(c.get_bake(running.bake_id).state) != "RUNNING":
                self.assertLess(time.monotonic(), deadline)
                time.sleep(0.05)
            c.cancel_bake(running.bake_id, finish=True)
            done = c.wait(running.bake_id)
            self.assertEqual(state_name(done.state), "SUCCEEDED", done.error_message)
            self.assertEqual(done.termination, "stopped")
            self.assertGreater(done.progress.paths, 0)
            self.assertIn("irradiance.exr", done.artifacts)
            c.download(running.bake_id, "manifest.json", pathlib.Path(out.name) / "m.json")
            manifest = json.loads((pathlib.Path(out.name) / "m.json").read_text())
            self.assertEqual(manifest["stats"]["termination"], "stopped")
            # The queued bake kept its request through the restart: it
            # finished as soon as it started, with nothing traced.
            other = c.wait(queued.bake_id)
            self.assertEqual(state_name(other.state), "SUCCEEDED", other.error_message)
            self.assertEqual(other.termination, "stopped")
            self.assertEqual(other.progress.paths, 0)
            # Finishing a finished bake changes nothing.
            again = c.cancel_bake(running.bake_id, finish=True)
            self.assertEqual(again.termination, "stopped")


class OneDaemonTest(unittest.TestCase):
    """A second luxeld on the same --data-dir, or on the same port, refuses to
    start with a message saying why; the first one keeps serving."""

    def setUp(self):
        self.binary = os.environ.get("LUXELD")
        if not self.binary or not os.access(self.binary, os.X_OK):
            self.skipTest("LUXELD does not name the luxeld binary")
        self.first = Luxeld(self.binary)
        self.first.start()
        self.addCleanup(self.first.cleanup)

    def refused(self, address, data_dir):
        """Runs a second daemon to its exit (a readiness probe would reach the
        first one on a shared port); returns its output."""
        p = subprocess.run([self.binary, "--listen", address, "--data-dir", str(data_dir)],
                           capture_output=True, text=True, timeout=60)
        self.assertEqual(p.returncode, 1, p.stderr)
        return p.stderr

    def assert_first_serves(self):
        with Client(self.first.address) as client:
            scene = client.upload_scene(FOLIAGE)
            self.assertIn(scene.scene_id, [s.scene_id for s in client.list_scenes()])

    def test_second_daemon_on_the_same_data_dir(self):
        message = self.refused(f"127.0.0.1:{free_loopback_port()}", self.first.data_dir)
        self.assertIn("is in use by another luxeld (pid %d" % self.first.process.pid, message)
        self.assert_first_serves()

    def test_second_daemon_on_the_same_port(self):
        other = tempfile.TemporaryDirectory(prefix="luxel_py_e2e_")
        self.addCleanup(other.cleanup)
        message = self.refused(self.first.address, pathlib.Path(other.name) / "data")
        self.assertIn("cannot listen on " + self.first.address, message)
        self.assert_first_serves()


if __name__ == "__main__":
    unittest.main()
