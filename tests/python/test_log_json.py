"""luxeld --log-format json: every line on stderr is one JSON object.

Runs a real daemon, makes RPCs (a bake, failing calls, a scene name with NUL,
CR, LF and quotes, a client-given x-request-id), stops it, and parses every
line of its log with Python's json module (independent of the daemon's
escaping). By hand:

    LUXELD=build/server/service/luxeld LUXEL_CACHE_DIR=build/cl-cache \
    PYTHONPATH=client/python:build/python:tests/python /usr/bin/python3 -m unittest -v test_log_json
"""

import json
import os
import pathlib
import re
import unittest

import grpc

from luxel_client import Client, LuxelError, luxel_pb2
from luxeld_process import Luxeld

SCENES = pathlib.Path(os.environ.get("LUXEL_SCENES_DIR",
                                     pathlib.Path(__file__).resolve().parents[2] / "scenes"))
SMALL = dict(resolution=16, samples_per_texel=4, paths_per_iteration=1024)
TS = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z$")
NASTY_NAME = 'bad\x00name\r\ninjected="1" \\ end'


class JsonLogTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        binary = os.environ.get("LUXELD")
        if not binary or not os.access(binary, os.X_OK):
            raise unittest.SkipTest("LUXELD does not name the luxeld binary")
        daemon = Luxeld(binary, ["--log-format", "json"])
        try:
            daemon.start()
            cls.calls = cls.make_calls(daemon)
            status = daemon.stop()
            cls.log = daemon.log()
        finally:
            daemon.cleanup()
        if status != 0:
            raise AssertionError(f"luxeld exited {status} after SIGTERM; log:\n{cls.log}")
        cls.records = [json.loads(line) for line in cls.log.splitlines()]

    @staticmethod
    def make_calls(daemon):
        calls = {}
        with Client(daemon.address, timeout=120) as client:
            scene = client.upload_scene(SCENES / "cornell_box.gltf")
            info = client.submit_bake(scene.scene_id, **SMALL)
            final = client.wait(info.bake_id)
            calls["bake_id"], calls["scene_id"] = info.bake_id, scene.scene_id
            calls["final_state"] = final.state
            with unittest.TestCase().assertRaises(LuxelError):
                client.get_bake("f" * 32)  # NOT_FOUND
            header = luxel_pb2.SceneUploadHeader(name=NASTY_NAME, format=luxel_pb2.SCENE_FORMAT_GLB,
                                                 total_size=4, sha256="0" * 64)
            with unittest.TestCase().assertRaises(LuxelError) as refused:
                client._upload(header, [b"glTF"])
            calls["refused_code"] = refused.exception.code
            # A client-given request id (cleaned: the space and '!' go) comes
            # back in the initial and trailing metadata, on success and error.
            stub = client._stub
            _, call = stub.GetServerStatus.with_call(
                luxel_pb2.GetServerStatusRequest(), metadata=(("x-request-id", "py-test.42 !"),))
            calls["ok_initial"] = dict(call.initial_metadata()).get("x-request-id")
            calls["ok_trailing"] = dict(call.trailing_metadata()).get("x-request-id")
            try:
                stub.GetScene(luxel_pb2.GetSceneRequest(scene_id="0" * 64),
                              metadata=(("x-request-id", "py-missing-scene"),))
            except grpc.RpcError as e:
                calls["error_code"] = e.code()
                calls["error_trailing"] = dict(e.trailing_metadata()).get("x-request-id")
            # Without one the daemon makes one up and still returns it.
            _, call = stub.ListScenes.with_call(luxel_pb2.ListScenesRequest())
            calls["generated"] = dict(call.initial_metadata()).get("x-request-id")
        return calls

    def rpc_lines(self, method):
        return [r for r in self.records if r.get("event") == "rpc" and r.get("method") == method]

    def test_every_line_is_an_object_with_ts_level_event(self):
        self.assertGreater(len(self.records), 10)
        for r in self.records:
            self.assertIsInstance(r, dict)
            self.assertRegex(r["ts"], TS)
            self.assertIn(r["level"], ("info", "warn", "error"))
            self.assertIsInstance(r["event"], str)
        self.assertEqual(self.records[-1]["event"], "stopped")

    def test_every_rpc_logs_method_request_id_code_duration(self):
        rpcs = [r for r in self.records if r["event"] == "rpc"]
        methods = {r["method"] for r in rpcs}
        self.assertTrue({"UploadScene", "SubmitBake", "WatchBake", "GetBake", "GetScene",
                         "GetServerStatus", "ListScenes"} <= methods, methods)
        for r in rpcs:
            self.assertRegex(r["request_id"], r"^[A-Za-z0-9._:-]{1,64}$")
            self.assertRegex(r["code"], r"^[A-Z_]+$")
            self.assertGreaterEqual(float(r["duration_ms"]), 0)
        ids = [r["request_id"] for r in rpcs]
        self.assertEqual(len(ids), len(set(ids)), "request ids repeat")
        self.assertEqual([r["code"] for r in self.rpc_lines("SubmitBake")], ["OK"])
        failed = [r for r in self.rpc_lines("GetBake") if r["code"] == "NOT_FOUND"]
        self.assertEqual(len(failed), 1)
        self.assertEqual(failed[0]["level"], "warn")

    def test_bake_lines_carry_ids_and_the_submitting_request(self):
        self.assertEqual(self.calls["final_state"], luxel_pb2.BAKE_STATE_SUCCEEDED)
        submitted = [r for r in self.records if r["event"] == "bake_submitted"]
        self.assertEqual(len(submitted), 1)
        self.assertEqual(submitted[0]["bake_id"], self.calls["bake_id"])
        self.assertEqual(submitted[0]["scene_id"], self.calls["scene_id"])
        # The handler's line and the RPC's line share the request id.
        self.assertEqual(submitted[0]["request_id"], self.rpc_lines("SubmitBake")[0]["request_id"])
        finished = [r for r in self.records if r["event"] == "bake_finished"]
        self.assertEqual([r["bake_id"] for r in finished], [self.calls["bake_id"]])

    def test_nasty_name_stays_one_line_and_decodes_exactly(self):
        self.assertEqual(self.calls["refused_code"], "INVALID_ARGUMENT")
        refused = [r for r in self.records if r["event"] == "upload_refused"]
        self.assertEqual(len(refused), 1, self.log)
        self.assertEqual(refused[0]["name"], NASTY_NAME)
        self.assertEqual(refused[0]["level"], "warn")
        raw = [line for line in self.log.splitlines() if "upload_refused" in line]
        self.assertEqual(len(raw), 1)
        self.assertNotIn("\r", raw[0])
        self.assertNotIn("\x00", raw[0])

    def test_request_id_from_the_client_is_cleaned_and_returned(self):
        self.assertEqual(self.calls["ok_initial"], "py-test.42")
        self.assertEqual(self.calls["ok_trailing"], "py-test.42")
        self.assertEqual(self.calls["error_code"], grpc.StatusCode.NOT_FOUND)
        self.assertEqual(self.calls["error_trailing"], "py-missing-scene")
        self.assertRegex(self.calls["generated"] or "", r"^[0-9a-f]{16}$")
        line = [r for r in self.rpc_lines("GetServerStatus") if r["request_id"] == "py-test.42"]
        self.assertEqual(len(line), 1)
        self.assertEqual(line[0]["code"], "OK")
        line = [r for r in self.rpc_lines("GetScene") if r["request_id"] == "py-missing-scene"]
        self.assertEqual([r["code"] for r in line], ["NOT_FOUND"])
        generated = [r for r in self.rpc_lines("ListScenes") if r["request_id"] == self.calls["generated"]]
        self.assertEqual(len(generated), 1)


if __name__ == "__main__":
    unittest.main()
