"""Bounds on luxeld's streams, against a real daemon on loopback: caps on
uploads and watchers (RESOURCE_EXHAUSTED naming the flag, slots usable again
once freed), the idle-upload deadline (DEADLINE_EXCEEDED, staging folder
gone, other clients served meanwhile), the thread count with 150 watchers,
and INVALID_ARGUMENT for request bytes that do not parse.

    LUXELD=build/server/service/luxeld LUXEL_CACHE_DIR=build/cl-cache \\
    PYTHONPATH=client/python:build/python:tests/python /usr/bin/python3 -m unittest -v test_service_limits
"""

import os
import pathlib
import threading
import time
import unittest

import grpc

from luxel_client import Client, luxel_pb2, luxel_pb2_grpc
from luxeld_process import Luxeld

SCENES = pathlib.Path(os.environ.get("LUXEL_SCENES_DIR",
                                     pathlib.Path(__file__).resolve().parents[2] / "scenes"))
CORNELL = SCENES / "cornell_box.gltf"
# A bake that runs until cancelled (or 60 s), with frequent snapshots so
# watchers have something to receive.
LONG = dict(resolution=32, samples_per_texel=0, time_budget_s=60, paths_per_iteration=1024,
            snapshot_interval_s=0.2, snapshot_max_side=32)
IDLE_TIMEOUT_S = 1.5


def thread_count(pid):
    return len(os.listdir(f"/proc/{pid}/task"))


def wait_until(predicate, timeout=20.0, what="condition"):
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.05)


class HeldUpload:
    """An UploadScene stream that sends a header (declaring 1000 bytes) and
    then, with `trickle`, one byte every 0.2 s until released; without it,
    nothing more (idle). The outcome is the call's status."""

    def __init__(self, stub, trickle):
        self.release = threading.Event()
        self.sent_header = threading.Event()
        self.trickle = trickle
        header = luxel_pb2.SceneUploadHeader(name="held.glb", format=luxel_pb2.SCENE_FORMAT_GLB,
                                             total_size=1000, sha256="0" * 64)

        def requests():
            yield luxel_pb2.UploadSceneRequest(header=header)
            self.sent_header.set()
            while not self.release.wait(0.2 if trickle else 30):
                if trickle:
                    yield luxel_pb2.UploadSceneRequest(chunk=b"x")

        self.started = time.monotonic()
        self.future = stub.UploadScene.future(requests())
        self.sent_header.wait(10)

    def outcome(self, timeout=30):
        try:
            self.future.result(timeout=timeout)
            return grpc.StatusCode.OK, ""
        except grpc.RpcError as e:
            return e.code(), e.details()


class StreamLimits(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.daemon = Luxeld(os.environ["LUXELD"], extra_args=[
            "--max-uploads", "2", "--max-uploads-per-client", "4",
            "--max-watchers", "1000", "--max-watchers-per-client", "3",
            "--max-downloads-per-client", "1",
            "--upload-idle-timeout", str(IDLE_TIMEOUT_S)]).start()
        cls.client = Client(cls.daemon.address)
        cls.channel = grpc.insecure_channel(cls.daemon.address)
        cls.stub = luxel_pb2_grpc.LuxelStub(cls.channel)

    @classmethod
    def tearDownClass(cls):
        cls.client.close()
        cls.channel.close()
        cls.daemon.stop()

    def status(self):
        return self.client.server_status()

    def staging(self):
        return list((self.daemon.data_dir / "staging").iterdir())

    def test_upload_cap_refuses_then_frees(self):
        held = [HeldUpload(self.stub, trickle=True) for _ in range(2)]
        wait_until(lambda: self.status().uploads == 2, what="2 open uploads")
        with self.assertRaises(grpc.RpcError) as refused:
            self.stub.UploadScene(iter([luxel_pb2.UploadSceneRequest()]), timeout=10)
        self.assertEqual(refused.exception.code(), grpc.StatusCode.RESOURCE_EXHAUSTED)
        self.assertIn("--max-uploads", refused.exception.details())
        for h in held:
            h.release.set()
        # A held upload ends short of its declared size: a specific status.
        for h in held:
            self.assertEqual(h.outcome()[0], grpc.StatusCode.DATA_LOSS)
        wait_until(lambda: self.status().uploads == 0, what="upload slots freed")
        info = self.client.upload_scene(CORNELL)  # the freed slot works
        self.assertEqual(len(info.scene_id), 64)
        self.assertEqual(self.staging(), [])

    def test_idle_upload_is_cut_and_others_are_served(self):
        idle = HeldUpload(self.stub, trickle=False)
        wait_until(lambda: len(self.staging()) == 1, what="the staging folder")
        # Meanwhile the daemon serves other calls, uploads included.
        self.assertEqual(len(self.client.upload_scene(CORNELL).scene_id), 64)
        self.client.list_scenes()
        code, details = idle.outcome(timeout=IDLE_TIMEOUT_S + 10)
        took = time.monotonic() - idle.started
        idle.release.set()
        self.assertEqual(code, grpc.StatusCode.DEADLINE_EXCEEDED, details)
        self.assertIn("--upload-idle-timeout", details)
        # The rule fires once the idle time has passed, never before (how much
        # later depends on the machine's load: not asserted).
        self.assertGreaterEqual(took, IDLE_TIMEOUT_S)
        self.assertEqual(self.staging(), [])
        wait_until(lambda: self.status().uploads == 0, what="upload slot freed")

    def test_watcher_cap_per_client_refuses_then_frees(self):
        scene = self.client.upload_scene(CORNELL)
        bake = self.client.submit_bake(scene.scene_id, **LONG)
        try:
            watches = [self.client.watch_bake(bake.bake_id) for _ in range(3)]
            for w in watches:
                next(iter(w))  # each stream is open and answered
            wait_until(lambda: self.status().watchers == 3, what="3 watchers")
            extra = self.stub.WatchBake(luxel_pb2.WatchBakeRequest(bake_id=bake.bake_id))
            with self.assertRaises(grpc.RpcError) as refused:
                next(extra)
            self.assertEqual(refused.exception.code(), grpc.StatusCode.RESOURCE_EXHAUSTED)
            self.assertIn("--max-watchers-per-client", refused.exception.details())
            watches[0].cancel()
            wait_until(lambda: self.status().watchers == 2, what="a watcher slot freed")
            again = self.client.watch_bake(bake.bake_id)
            self.assertTrue(next(iter(again)).info.bake_id == bake.bake_id)
            for w in watches[1:] + [again]:
                w.cancel()
        finally:
            self.client.cancel_bake(bake.bake_id)
        wait_until(lambda: self.status().watchers == 0, what="every watcher gone")

    def test_download_cap_per_client_refuses_then_frees(self):
        scene = self.client.upload_scene(CORNELL)
        # A float EXR of 512x512 texels, read through a channel without BDP
        # probing (the HTTP/2 window stays at 64 KiB): an unread download
        # stays open on the daemon.
        bake = self.client.submit_bake(scene.scene_id, resolution=512, samples_per_texel=1)
        info = self.client.wait(bake.bake_id)
        request = luxel_pb2.DownloadResultRequest(bake_id=bake.bake_id, artifact="irradiance.exr")
        slow = grpc.insecure_channel(self.daemon.address, options=[("grpc.http2.bdp_probe", 0)])
        self.addCleanup(slow.close)
        held = luxel_pb2_grpc.LuxelStub(slow).DownloadResult(request)
        first = next(held)
        self.assertGreater(first.total_size, 1 << 20, "the artifact must outgrow the window")
        wait_until(lambda: self.status().downloads == 1, what="1 open download")
        with self.assertRaises(grpc.RpcError) as refused:
            next(self.stub.DownloadResult(request))
        self.assertEqual(refused.exception.code(), grpc.StatusCode.RESOURCE_EXHAUSTED)
        self.assertIn("--max-downloads-per-client", refused.exception.details())
        held.cancel()
        wait_until(lambda: self.status().downloads == 0, what="the download slot freed")
        d = self.client.download(bake.bake_id, "manifest.json",
                                 pathlib.Path(self.daemon.tmp.name) / "manifest.json")
        self.assertGreater(d.size, 0)
        self.assertIn("manifest.json", info.artifacts)

    def test_malformed_request_bytes_are_invalid_argument(self):
        for method in ("GetBake", "SubmitBake", "GetServerStatus", "WatchBake", "DownloadResult"):
            streaming = method in ("WatchBake", "DownloadResult")
            # Raw bytes both ways (no serializer).
            call = (self.channel.unary_stream if streaming else self.channel.unary_unary)(
                f"/luxel.v1.Luxel/{method}")
            for junk in (b"\x0a\x64abc", b"\xff\xff\xff\xff\xff"):
                with self.subTest(method=method, junk=junk):
                    with self.assertRaises(grpc.RpcError) as e:
                        result = call(junk, timeout=10)
                        if streaming:
                            list(result)
                    self.assertEqual(e.exception.code(), grpc.StatusCode.INVALID_ARGUMENT,
                                     e.exception.details())
                    self.assertIn("malformed", e.exception.details())
        self.status()  # and the daemon lives on


class ManyWatchers(unittest.TestCase):
    """150 watchers of one bake: with one thread per stream (the sync API)
    the daemon grew by 150 threads; the callback reactors add none."""

    WATCHERS = 150
    MAX_EXTRA_THREADS = 16  # gRPC's own pollers/executor may grow a little

    def test_threads_stay_bounded(self):
        daemon = Luxeld(os.environ["LUXELD"],
                        extra_args=["--max-watchers-per-client", "1000"]).start()
        try:
            with Client(daemon.address) as client:
                scene = client.upload_scene(CORNELL)
                bake = client.submit_bake(scene.scene_id, **LONG)
                time.sleep(0.5)
                before = thread_count(daemon.process.pid)
                watches = [client.watch_bake(bake.bake_id) for _ in range(self.WATCHERS)]
                for w in watches:
                    next(iter(w))
                wait_until(lambda: client.server_status().watchers == self.WATCHERS,
                           what=f"{self.WATCHERS} watchers")
                during = thread_count(daemon.process.pid)
                print(f"\nluxeld threads: {before} before, {during} with {self.WATCHERS} watchers")
                for w in watches:
                    w.cancel()
                client.cancel_bake(bake.bake_id)
                self.assertLessEqual(during - before, self.MAX_EXTRA_THREADS)
        finally:
            daemon.stop()


if __name__ == "__main__":
    unittest.main()
