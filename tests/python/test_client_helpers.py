"""The Python client's pieces that need no daemon: stub loading, resource
discovery and hashing of scene uploads, chunking, settings mapping.

Run: PYTHONPATH=client/python:<build>/python /usr/bin/python3 -m unittest tests/python/test_client_helpers.py
"""

import hashlib
import json
import os
import pathlib
import tempfile
import unittest

import luxel_client
from luxel_client import LuxelError, collect_scene_files, luxel_pb2, make_settings, referenced_uris
from luxel_client import scene_files
from luxel_client.scene_files import CHUNK_SIZE, iter_chunks, sha256_file

SCENES = pathlib.Path(os.environ.get("LUXEL_SCENES_DIR",
                                     pathlib.Path(__file__).resolve().parents[2] / "scenes"))


class ResourceDiscoveryTest(unittest.TestCase):
    def test_lists_buffers_then_images_skipping_data_uris_and_repeats(self):
        gltf = {"buffers": [{"uri": "a.bin"}, {"uri": "data:application/octet-stream;base64,AAAA"},
                            {"byteLength": 4}],
                "images": [{"uri": "tex/b%20c.png"}, {"uri": "a.bin"}, {"bufferView": 0}]}
        self.assertEqual(referenced_uris(gltf),
                         [("a.bin", "buffers[0].uri"), ("tex/b%20c.png", "images[0].uri")])

    def test_cornell_box_brings_its_bin(self):
        fmt, files = collect_scene_files(SCENES / "cornell_box.gltf")
        self.assertEqual(fmt, "gltf")
        self.assertEqual([f.uri for f in files], ["", "cornell_box.bin"])
        for f in files:
            data = f.path.read_bytes()
            self.assertEqual(f.size, len(data))
            self.assertEqual(f.sha256, hashlib.sha256(data).hexdigest())

    def test_scene_id_covers_the_resources(self):
        gltf_path = SCENES / "cornell_box.gltf"
        main, bin_bytes = gltf_path.read_bytes(), (SCENES / "cornell_box.bin").read_bytes()
        manifest = (f"luxel-scene-v1\n{hashlib.sha256(main).hexdigest()}\n"
                    f"cornell_box.bin\t{len(bin_bytes)}\t{hashlib.sha256(bin_bytes).hexdigest()}\n")
        self.assertEqual(luxel_client.scene_id(gltf_path), hashlib.sha256(manifest.encode()).hexdigest())
        glb = SCENES / "foliage_instanced.glb"
        self.assertEqual(luxel_client.scene_id(glb), hashlib.sha256(glb.read_bytes()).hexdigest())
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            (tmp / "cornell_box.gltf").write_bytes(main)
            (tmp / "cornell_box.bin").write_bytes(bin_bytes)
            self.assertEqual(luxel_client.scene_id(tmp / "cornell_box.gltf"), luxel_client.scene_id(gltf_path))
            (tmp / "cornell_box.bin").write_bytes(bin_bytes[:-1] + bytes([bin_bytes[-1] ^ 1]))
            self.assertNotEqual(luxel_client.scene_id(tmp / "cornell_box.gltf"),
                                luxel_client.scene_id(gltf_path))

    def test_scene_id_sorts_resources_by_uri_bytes(self):
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            (tmp / "b.bin").write_bytes(b"bb")
            (tmp / "Z.png").write_bytes(b"z")
            # Listed b.bin first; byte order puts "Z.png" (0x5a) before "b.bin" (0x62).
            (tmp / "s.gltf").write_text(json.dumps({"buffers": [{"uri": "b.bin"}], "images": [{"uri": "Z.png"}]}))
            main = hashlib.sha256((tmp / "s.gltf").read_bytes()).hexdigest()
            manifest = (f"luxel-scene-v1\n{main}\n"
                        f"Z.png\t1\t{hashlib.sha256(b'z').hexdigest()}\n"
                        f"b.bin\t2\t{hashlib.sha256(b'bb').hexdigest()}\n")
            self.assertEqual(luxel_client.scene_id(tmp / "s.gltf"), hashlib.sha256(manifest.encode()).hexdigest())

    def test_glb_is_one_file(self):
        fmt, files = collect_scene_files(SCENES / "foliage_instanced.glb")
        self.assertEqual(fmt, "glb")
        self.assertEqual(len(files), 1)

    def test_percent_encoded_uri_is_sent_verbatim_and_read_decoded(self):
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            (tmp / "my tex.png").write_bytes(b"\x89PNG fake")
            (tmp / "s.gltf").write_text(json.dumps({"images": [{"uri": "my%20tex.png"}]}))
            _, files = collect_scene_files(tmp / "s.gltf")
            self.assertEqual(files[1].uri, "my%20tex.png")
            self.assertEqual(files[1].path, tmp / "my tex.png")

    def test_malformed_percent_escapes_are_refused_like_the_daemon(self):
        for bad in ("a%zz.bin", "a%4.bin", "a%.bin", "a%00.bin"):
            with self.assertRaises(LuxelError) as caught:
                scene_files.percent_decode_uri(bad, "buffers[0].uri")
            self.assertEqual(caught.exception.code, "INVALID_ARGUMENT")
            self.assertIn("buffers[0].uri", str(caught.exception))
        self.assertEqual(scene_files.percent_decode_uri("a+b%20c%C3%A9.bin", "w"), "a+b c\u00e9.bin")

    def test_missing_or_escaping_resources_are_refused_naming_the_field(self):
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            cases = {"gone.bin": "NOT_FOUND", "../up.bin": "INVALID_ARGUMENT",
                     "/etc/passwd": "INVALID_ARGUMENT", "http://x/y.bin": "INVALID_ARGUMENT"}
            for uri, code in cases.items():
                (tmp / "s.gltf").write_text(json.dumps({"buffers": [{"uri": uri}]}))
                with self.assertRaises(LuxelError) as caught:
                    collect_scene_files(tmp / "s.gltf")
                self.assertEqual(caught.exception.code, code, uri)
                self.assertIn("buffers[0].uri", caught.exception.message)
                self.assertTrue(caught.exception.local)


class HashingAndChunkingTest(unittest.TestCase):
    def test_chunks_are_64k_per_file_and_rebuild_the_files(self):
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            sizes = [0, 1, CHUNK_SIZE, CHUNK_SIZE + 1, 3 * CHUNK_SIZE - 7]
            payloads = [os.urandom(n) for n in sizes]
            files = []
            for i, payload in enumerate(payloads):
                path = tmp / f"f{i}"
                path.write_bytes(payload)
                digest, size = sha256_file(path)
                self.assertEqual((digest, size), (hashlib.sha256(payload).hexdigest(), len(payload)))
                files.append(luxel_client.SceneFile(f"f{i}", path, size, digest))
            chunks = list(iter_chunks(files))
            self.assertTrue(all(0 < len(c) <= CHUNK_SIZE for c in chunks))
            # A chunk never spans two files: the per-file chunk counts add up.
            expected = sum(-(-n // CHUNK_SIZE) for n in sizes)
            self.assertEqual(len(chunks), expected)
            self.assertEqual(b"".join(chunks), b"".join(payloads))


class SettingsTest(unittest.TestCase):
    def test_keywords_map_onto_bake_settings(self):
        s = make_settings(resolution=32, samples_per_texel=8, max_bounces=0, filter="gaussian",
                          snapshot_format="EXR", sky=(0.5, 0.6, 0.7),
                          sun={"direction": [0, -1, 0], "illuminance": 2.0}, priority=-3)
        self.assertEqual(s.resolution, 32)
        self.assertTrue(s.HasField("max_bounces"))  # optional: 0 differs from unset
        self.assertEqual(s.max_bounces, 0)
        self.assertEqual(s.filter, luxel_pb2.FILTER_GAUSSIAN)
        self.assertEqual(s.snapshot_format, luxel_pb2.SNAPSHOT_FORMAT_EXR)
        self.assertEqual(s.sky.kind, luxel_pb2.Sky.KIND_CONSTANT)
        for got, want in zip(s.sky.color, (0.5, 0.6, 0.7)):
            self.assertAlmostEqual(got, want, places=6)
        self.assertEqual(list(s.sun.direction), [0, -1, 0])
        self.assertEqual(s.priority, -3)
        self.assertFalse(make_settings(resolution=8).HasField("max_bounces"))

    def test_typed_lists_and_enums_take_names(self):
        s = make_settings(encodings="irradiance,sh2,ambient-dice9", solver="progressive-nn",
                          target_metric="rmse")
        self.assertEqual(list(s.encodings), [luxel_pb2.ENCODING_IRRADIANCE, luxel_pb2.ENCODING_SH2,
                                             luxel_pb2.ENCODING_AMBIENT_DICE9])
        self.assertEqual(s.solver, luxel_pb2.SOLVER_PROGRESSIVE_NN)
        self.assertEqual(s.target_metric, luxel_pb2.TARGET_METRIC_RMSE)
        # The field's name before it was typed still works, as does a list.
        old = make_settings(encoding="sg12-hemi")
        self.assertEqual(list(old.encodings), [luxel_pb2.ENCODING_SG12_HEMI])
        self.assertEqual(list(make_settings(encodings=["sh1", "SG6"]).encodings),
                         [luxel_pb2.ENCODING_SH1, luxel_pb2.ENCODING_SG6])

    def test_placements_take_a_list_of_dicts(self):
        s = make_settings(placements=[{"node": 2, "scale_offset": (0.5, 0.25, 0.125, 0.75)},
                                      {"node": 3, "instance": 1, "scale_offset": [1, 1, 0, 0],
                                       "page": 2}])
        self.assertEqual(len(s.placements), 2)
        self.assertEqual(s.placements[0].node, 2)
        self.assertFalse(s.placements[0].HasField("instance"))
        self.assertEqual(list(s.placements[0].scale_offset), [0.5, 0.25, 0.125, 0.75])
        self.assertEqual((s.placements[1].instance, s.placements[1].page), (1, 2))
        with self.assertRaises(LuxelError) as e:
            make_settings(placements=[{"node": 0}, {"nod": 1}])
        self.assertIn("settings.placements[1].nod", str(e.exception))

    def test_schema_comes_from_the_build(self):
        from luxel_client import settings
        self.assertIn("max_bounces", settings.SCHEMA, "settings_schema.json missing beside the stubs")
        d = settings.defaults()
        self.assertEqual((d["max_bounces"], d["resolution"], d["seed"]), (4, 0, 1))
        self.assertEqual((d["texel_density"], d["max_resolution"]), (40, 1024))
        self.assertNotIn("rr_depth", d)  # local only
        self.assertIn("[0, 64]", settings.describe("max_bounces"))
        # Every API setting of the schema is a field of the proto.
        for name, entry in settings.SCHEMA.items():
            if entry["scope"] == "local_only":
                continue
            message, field = luxel_pb2.BakeSettings.DESCRIPTOR, None
            for part in name.split("."):
                field = message.fields_by_name.get(part)
                self.assertIsNotNone(field, name)
                message = field.message_type
        with self.assertRaises(LuxelError) as caught:
            make_settings(rr_depth=2)
        self.assertIn("settings.rr_depth: only in-process", caught.exception.message)

    def test_bad_keywords_name_the_field(self):
        for kwargs, field in [({"resolutoin": 3}, "settings.resolutoin"),
                              ({"resolution": -1}, "settings.resolution"),
                              ({"filter": "bilinear"}, "settings.filter"),
                              ({"encodings": "sh9"}, "settings.encodings"),
                              ({"sun": {"power": 1}}, "settings.sun.power")]:
            with self.assertRaises(LuxelError) as caught:
                make_settings(**kwargs)
            self.assertEqual(caught.exception.code, "INVALID_ARGUMENT")
            self.assertIn(field, caught.exception.message)

    def test_state_names(self):
        self.assertEqual(luxel_client.state_value("running"), luxel_pb2.BAKE_STATE_RUNNING)
        self.assertEqual(luxel_client.state_value("BAKE_STATE_QUEUED"), luxel_pb2.BAKE_STATE_QUEUED)
        self.assertEqual(luxel_client.state_name(luxel_pb2.BAKE_STATE_SUCCEEDED), "SUCCEEDED")


if __name__ == "__main__":
    unittest.main()
