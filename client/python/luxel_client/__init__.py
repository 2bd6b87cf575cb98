"""Python client for the Luxel lightmap baking daemon (luxeld, API luxel.v1).

    from luxel_client import Client
    with Client("127.0.0.1:50051") as luxel:
        outcome = luxel.bake("scenes/cornell_box.gltf", "out", resolution=128, samples_per_texel=64)

See client/python/README.md. The generated protobuf modules are found through
LUXEL_PYTHON_STUBS, PYTHONPATH or <repo>/build/python (see _stubs.py).
"""

from ._stubs import luxel_pb2, luxel_pb2_grpc
from .client import DEFAULT_SERVER, BakeOutcome, BakeWatch, Client, Download
from .errors import LuxelError
from .scene_files import (CHUNK_SIZE, SceneFile, collect_scene_files, referenced_uris, scene_id,
                          scene_id_of_files, sha256_file)
from .settings import make_settings, state_name, state_value

__all__ = [
    "BakeOutcome", "BakeWatch", "CHUNK_SIZE", "Client", "DEFAULT_SERVER", "Download", "LuxelError",
    "SceneFile", "collect_scene_files", "luxel_pb2", "luxel_pb2_grpc", "make_settings",
    "referenced_uris", "scene_id", "scene_id_of_files", "sha256_file", "state_name", "state_value",
]
