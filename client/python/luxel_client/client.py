"""Client for the luxel.v1 bake service (the luxeld daemon).

Calls return the protobuf messages of proto/luxel/v1/luxel.proto (SceneInfo,
BakeInfo, BakeEvent, ...); every failure is raised as a LuxelError carrying
the gRPC status code name and the daemon's message.
"""

import dataclasses
import hashlib
import os
import pathlib
import tempfile
import threading

import grpc

from ._stubs import luxel_pb2, luxel_pb2_grpc
from .errors import LuxelError
from .scene_files import collect_scene_files, iter_chunks
from .settings import make_settings, state_name, state_value

DEFAULT_SERVER = "127.0.0.1:50051"
# Snapshots in EXR format of a large lightmap exceed gRPC's 4 MiB default.
MAX_MESSAGE_BYTES = 512 * 1024 * 1024
_FINISHED = {"SUCCEEDED", "FAILED", "CANCELLED"}


@dataclasses.dataclass(frozen=True)
class Download:
    """A verified artifact on disk."""
    path: pathlib.Path
    size: int      # bytes
    sha256: str    # hex, checked against the daemon's final checksum


@dataclasses.dataclass(frozen=True)
class BakeOutcome:
    """What Client.bake() returns: the scene, the finished job and its files."""
    scene: object          # luxel_pb2.SceneInfo
    info: object           # luxel_pb2.BakeInfo, final state
    files: dict            # artifact name -> Download


class BakeWatch:
    """The events of one WatchBake stream: iterate it for luxel_pb2.BakeEvent
    messages (the first is the bake's current state, the last has ``final``
    set). cancel() — or leaving a ``with`` block — closes the stream; the bake
    itself goes on.

    latest_only: a consumer slower than the bake's snapshot rate would
    otherwise work through a backlog (gRPC's transport buffers events the
    daemon already sent, so the daemon cannot coalesce them for a slow
    reader). With latest_only a thread drains the stream and iteration
    yields only the newest event (the final event is never dropped)."""

    def __init__(self, call, latest_only=False):
        self._call = call
        self._latest_only = latest_only
        if latest_only:
            self._cond = threading.Condition()
            self._newest = None      # newest unread event
            self._done = False       # stream ended (normally or with an error)
            self._error = None
            self._thread = threading.Thread(target=self._drain, daemon=True)
            self._thread.start()

    def _next_raw(self):
        try:
            return next(self._call)
        except grpc.RpcError as e:
            if e.code() == grpc.StatusCode.CANCELLED and self._call.cancelled():
                raise StopIteration from None  # we closed it ourselves
            raise LuxelError.from_rpc_error(e) from None

    def _drain(self):
        try:
            for event in iter(self._next_raw, None):
                with self._cond:
                    self._newest = event
                    self._cond.notify()
                if event.final:
                    break
        except StopIteration:
            pass
        except LuxelError as e:
            with self._cond:
                self._error = e
        with self._cond:
            self._done = True
            self._cond.notify()

    def __iter__(self):
        return self

    def __next__(self):
        if not self._latest_only:
            return self._next_raw()
        with self._cond:
            while self._newest is None and not self._done:
                self._cond.wait()
            if self._newest is not None:
                event, self._newest = self._newest, None
                return event
            if self._error is not None:
                raise self._error
            raise StopIteration

    def cancel(self):
        self._call.cancel()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.cancel()
        return False


class Client:
    """A connection to one daemon.

    server:  "host:port" of luxeld.
    token:   bearer token, sent as "authorization: Bearer <token>" with every call.
    tls_ca:  path of a PEM CA certificate; when given the channel uses TLS.
    timeout: seconds allowed for each unary call (streams have no deadline).
    """

    def __init__(self, server=DEFAULT_SERVER, token=None, tls_ca=None, timeout=60.0):
        options = [("grpc.max_receive_message_length", MAX_MESSAGE_BYTES),
                   ("grpc.max_send_message_length", MAX_MESSAGE_BYTES)]
        if tls_ca:
            with open(tls_ca, "rb") as f:
                credentials = grpc.ssl_channel_credentials(root_certificates=f.read())
            self._channel = grpc.secure_channel(server, credentials, options=options)
        else:
            self._channel = grpc.insecure_channel(server, options=options)
        self._stub = luxel_pb2_grpc.LuxelStub(self._channel)
        self._metadata = (("authorization", f"Bearer {token}"),) if token else ()
        self._timeout = timeout
        self.server = server

    # ------------------------------------------------------------ plumbing

    def close(self):
        self._channel.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def wait_ready(self, timeout=10.0):
        """Blocks until a daemon answers (any answer, UNAUTHENTICATED included);
        LuxelError UNAVAILABLE after ``timeout`` s. A wait-for-ready call rather
        than grpc.channel_ready_future, whose polling thread can outlive the
        wait and fail on a channel closed soon after."""
        try:
            self._stub.GetServerStatus(luxel_pb2.GetServerStatusRequest(), timeout=timeout,
                                       metadata=self._metadata, wait_for_ready=True)
        except grpc.RpcError as e:
            if e.code() in (grpc.StatusCode.UNAVAILABLE, grpc.StatusCode.DEADLINE_EXCEEDED):
                raise LuxelError("UNAVAILABLE", f"no daemon answered at {self.server} within {timeout} s",
                                 local=True) from None

    def _unary(self, method, request):
        try:
            return method(request, timeout=self._timeout, metadata=self._metadata)
        except grpc.RpcError as e:
            raise LuxelError.from_rpc_error(e) from None

    # ------------------------------------------------------------ scenes

    def upload_scene(self, path, name=None):
        """Uploads a .gltf (with the buffers and images it references by
        relative uri) or a .glb; returns the daemon's SceneInfo. The scene id
        covers the main file and its resources (see scene_files.scene_id);
        re-uploading stored content is cheap on the daemon side
        (already_stored is set)."""
        fmt, files = collect_scene_files(path)
        main = files[0]
        header = luxel_pb2.SceneUploadHeader(
            name=name or main.path.name,
            format=luxel_pb2.SCENE_FORMAT_GLB if fmt == "glb" else luxel_pb2.SCENE_FORMAT_GLTF,
            total_size=main.size,
            sha256=main.sha256,
            resources=[luxel_pb2.ResourceHeader(uri=f.uri, size=f.size, sha256=f.sha256)
                       for f in files[1:]])
        return self._upload(header, iter_chunks(files))

    def _upload(self, header, chunks):
        """Sends a header and byte chunks as one UploadScene stream. Exposed
        (with a leading underscore) so tests can send deliberately wrong headers."""
        def requests():
            yield luxel_pb2.UploadSceneRequest(header=header)
            for chunk in chunks:
                yield luxel_pb2.UploadSceneRequest(chunk=chunk)
        return self._unary(self._stub.UploadScene, requests())

    def get_scene(self, scene_id):
        return self._unary(self._stub.GetScene, luxel_pb2.GetSceneRequest(scene_id=scene_id))

    def list_scenes(self):
        """All stored scenes, a list of SceneInfo."""
        return list(self._unary(self._stub.ListScenes, luxel_pb2.ListScenesRequest()).scenes)

    def delete_scene(self, scene_id):
        """Deletes a stored scene (FAILED_PRECONDITION while a bake uses it)."""
        self._unary(self._stub.DeleteScene, luxel_pb2.DeleteSceneRequest(scene_id=scene_id))

    # ------------------------------------------------------------ bakes

    def submit_bake(self, scene_id, idempotency_key=None, **settings):
        """Queues a bake of a stored scene; returns its BakeInfo. Keyword
        arguments are BakeSettings fields (see settings.py), e.g.
        ``submit_bake(sid, resolution=256, samples_per_texel=64, filter="gaussian")``.
        With an idempotency_key a retry returns the job the first call made."""
        request = luxel_pb2.SubmitBakeRequest(scene_id=scene_id, settings=make_settings(**settings),
                                              idempotency_key=idempotency_key or "")
        return self._unary(self._stub.SubmitBake, request)

    def get_bake(self, bake_id):
        return self._unary(self._stub.GetBake, luxel_pb2.GetBakeRequest(bake_id=bake_id))

    def list_bakes(self, states=None):
        """Bakes, optionally only those in ``states`` (names like "RUNNING" or numbers)."""
        request = luxel_pb2.ListBakesRequest(states=[state_value(s) for s in states or []])
        return list(self._unary(self._stub.ListBakes, request).bakes)

    def cancel_bake(self, bake_id, finish=False):
        """Cancels a queued or running bake and returns at once: a queued bake
        comes back CANCELLED, a running one RUNNING with cancel_requested set,
        and ends CANCELLED within a fraction of a second (wait() for it).
        finish=True keeps it instead: the bake stops tracing and completes
        from the samples it has (SUCCEEDED, termination "stopped")."""
        return self._unary(self._stub.CancelBake,
                           luxel_pb2.CancelBakeRequest(bake_id=bake_id, finish=finish))

    def watch_bake(self, bake_id, latest_only=False):
        """A BakeWatch over the bake's events (iterate it; cancel() to stop).
        latest_only=True for slow consumers (e.g. an editor redrawing a
        preview): stale events are skipped, the newest and the final one kept."""
        call = self._stub.WatchBake(luxel_pb2.WatchBakeRequest(bake_id=bake_id), metadata=self._metadata)
        return BakeWatch(call, latest_only=latest_only)

    def server_status(self):
        return self._unary(self._stub.GetServerStatus, luxel_pb2.GetServerStatusRequest())

    # ------------------------------------------------------------ results

    def download(self, bake_id, artifact, path):
        """Streams an artifact of a finished bake to ``path`` (a file, or a
        folder to put ``artifact`` in: an existing one, or a path ending in "/"). The bytes go to a temporary file beside
        it, which replaces ``path`` only when size and sha256 match the daemon's
        (DATA_LOSS otherwise, and nothing is left behind). Returns a Download."""
        as_folder = str(path).endswith(("/", os.sep)) or pathlib.Path(path).is_dir()
        path = pathlib.Path(path) / artifact if as_folder else pathlib.Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        request = luxel_pb2.DownloadResultRequest(bake_id=bake_id, artifact=artifact)
        fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
        try:
            with os.fdopen(fd, "wb") as out:
                size, digest, expected_size, expected_digest = self._receive(request, out)
                out.flush()
                os.fsync(out.fileno())
            where = f"{bake_id}/{artifact}"
            if not expected_digest:
                raise LuxelError("DATA_LOSS", f"{where}: the stream ended without a checksum", local=True)
            if expected_size and size != expected_size:
                raise LuxelError("DATA_LOSS", f"{where}: got {size} bytes, expected {expected_size}", True)
            if digest != expected_digest.lower():
                raise LuxelError("DATA_LOSS", f"{where}: sha256 {digest} != announced {expected_digest}", True)
            os.replace(tmp_name, path)
        except BaseException:
            if os.path.exists(tmp_name):
                os.unlink(tmp_name)
            raise
        return Download(path, size, digest)

    def _receive(self, request, out):
        digest = hashlib.sha256()
        size = expected_size = 0
        expected_digest = ""
        try:
            for message in self._stub.DownloadResult(request, metadata=self._metadata):
                if message.total_size:
                    expected_size = message.total_size
                if message.chunk:
                    out.write(message.chunk)
                    digest.update(message.chunk)
                    size += len(message.chunk)
                if message.sha256:
                    expected_digest = message.sha256
        except grpc.RpcError as e:
            raise LuxelError.from_rpc_error(e) from None
        return size, digest.hexdigest(), expected_size, expected_digest

    def bake(self, scene_path, out_dir, on_event=None, idempotency_key=None, **settings):
        """Upload, submit, watch until the end, download every artifact into
        ``out_dir``. ``on_event(event)`` sees every BakeEvent. Raises LuxelError
        (code "ABORTED") when the bake ends FAILED or CANCELLED."""
        scene = self.upload_scene(scene_path)
        info = self.submit_bake(scene.scene_id, idempotency_key=idempotency_key, **settings)
        info = self.wait(info.bake_id, on_event)
        state = state_name(info.state)
        if state != "SUCCEEDED":
            why = f": {info.error_message}" if info.error_message else ""
            raise LuxelError("ABORTED", f"bake {info.bake_id} ended {state}{why}", local=True)
        files = {name: self.download(info.bake_id, name, pathlib.Path(out_dir) / name)
                 for name in info.artifacts}
        return BakeOutcome(scene, info, files)

    def wait(self, bake_id, on_event=None):
        """Watches a bake until its final event; returns the final BakeInfo.
        A stream that ends without a final event (daemon restart) is followed
        by a GetBake, so the caller always learns the state."""
        last = None
        with self.watch_bake(bake_id) as watch:
            for event in watch:
                if on_event:
                    on_event(event)
                last = event.info
                if event.final:
                    return event.info
        info = self.get_bake(bake_id)
        if state_name(info.state) in _FINISHED:
            return info
        raise LuxelError("UNAVAILABLE", f"watch of bake {bake_id} ended early in state "
                         f"{state_name((last or info).state)}", local=True)
