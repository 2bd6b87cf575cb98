"""The files of a scene upload: the main .gltf/.glb and the external resources
a .gltf references. Pure Python (no gRPC), so it is testable without a daemon.
"""

import dataclasses
import hashlib
import json
import pathlib
import urllib.parse

from .errors import LuxelError

CHUNK_SIZE = 64 * 1024  # bytes per UploadScene chunk


@dataclasses.dataclass(frozen=True)
class SceneFile:
    """One file of an upload. ``uri`` is the relative uri exactly as the .gltf
    writes it (empty for the main file); ``path`` is where it lies on disk."""
    uri: str
    path: pathlib.Path
    size: int
    sha256: str


def sha256_file(path):
    """Hex sha256 and size in bytes of a file, read in CHUNK_SIZE pieces."""
    digest = hashlib.sha256()
    size = 0
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(CHUNK_SIZE), b""):
            digest.update(chunk)
            size += len(chunk)
    return digest.hexdigest(), size


def scene_format(path):
    """"glb" for a binary glTF (by its magic, else its extension), "gltf" otherwise."""
    path = pathlib.Path(path)
    with open(path, "rb") as f:
        if f.read(4) == b"glTF":
            return "glb"
    return "glb" if path.suffix.lower() == ".glb" else "gltf"


def referenced_uris(gltf_json):
    """External resource uris of a parsed .gltf: buffers[].uri, then images[].uri,
    in the order listed, skipping data: URIs and repeats. Each entry is
    (uri, where) with ``where`` naming the field, e.g. "buffers[0].uri"."""
    seen = set()
    found = []
    for array in ("buffers", "images"):
        for index, item in enumerate(gltf_json.get(array) or []):
            uri = item.get("uri") if isinstance(item, dict) else None
            if not uri or uri.startswith("data:") or uri in seen:
                continue
            seen.add(uri)
            found.append((uri, f"{array}[{index}].uri"))
    return found


_HEX = "0123456789abcdefABCDEF"


def percent_decode_uri(uri, where):
    """The uri's path with percent-escapes decoded, by the rule the engine,
    the daemon and the CLI share (server/engine/common/uri.h): a '%' not
    followed by two hex digits, and '%00', are refused; '+' stays '+'."""
    out = bytearray()
    raw = uri.encode("utf-8")
    i = 0
    while i < len(raw):
        if raw[i] != ord("%"):
            out.append(raw[i])
            i += 1
            continue
        escape = raw[i:i + 3].decode("utf-8", "replace")
        if len(escape) < 3 or escape[1] not in _HEX or escape[2] not in _HEX:
            raise LuxelError("INVALID_ARGUMENT",
                             f"{where}: uri '{uri}': malformed percent-escape '{escape}' at byte {i} "
                             "(expected '%' and two hex digits)", local=True)
        if escape[1:] == "00":
            raise LuxelError("INVALID_ARGUMENT",
                             f"{where}: uri '{uri}': '%00' at byte {i} would put a NUL byte in a file name",
                             local=True)
        out.append(int(escape[1:], 16))
        i += 3
    return out.decode("utf-8", "surrogateescape")


def _resource_path(base_dir, uri, where):
    """Where a relative uri points on disk; refuses absolute and escaping uris,
    which the daemon could not store beside the scene either."""
    parsed = urllib.parse.urlsplit(uri)
    if parsed.scheme or parsed.netloc or uri.startswith("/"):
        raise LuxelError("INVALID_ARGUMENT", f"{where}: '{uri}' is not a relative uri", local=True)
    relative = pathlib.PurePosixPath(percent_decode_uri(parsed.path, where))
    if ".." in relative.parts:
        raise LuxelError("INVALID_ARGUMENT", f"{where}: '{uri}' leaves the scene folder", local=True)
    path = base_dir.joinpath(*relative.parts)
    if not path.is_file():
        raise LuxelError("NOT_FOUND", f"{where}: '{uri}' not found at {path}", local=True)
    return path


def collect_scene_files(path):
    """The files to upload for the scene at ``path``: the main file first, then
    (for a .gltf) each external resource in the order of referenced_uris().
    Returns (format, [SceneFile, ...])."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise LuxelError("NOT_FOUND", f"scene file not found: {path}", local=True)
    fmt = scene_format(path)
    digest, size = sha256_file(path)
    files = [SceneFile("", path, size, digest)]
    if fmt == "gltf":
        try:
            gltf = json.loads(path.read_text(encoding="utf-8"))
        except (ValueError, UnicodeDecodeError) as e:
            raise LuxelError("INVALID_ARGUMENT", f"{path}: not a JSON glTF: {e}", local=True) from e
        for uri, where in referenced_uris(gltf):
            resource = _resource_path(path.parent, uri, where)
            digest, size = sha256_file(resource)
            files.append(SceneFile(uri, resource, size, digest))
    return fmt, files


def scene_id_of_files(files):
    """The scene id the daemon gives an upload of ``files`` (main file first,
    as collect_scene_files returns them); the rule is in luxel.proto's header
    comment. Without external resources it is the main file's sha256;
    otherwise the sha256 of "luxel-scene-v1\\n" + "<main sha256>\\n" + one
    line "<uri>\\t<size>\\t<sha256>\\n" per resource, sorted by uri as
    written (byte order), so a changed .bin is a different scene."""
    main, resources = files[0], files[1:]
    if not resources:
        return main.sha256
    manifest = b"luxel-scene-v1\n" + main.sha256.encode("ascii") + b"\n"
    for r in sorted(resources, key=lambda f: f.uri.encode("utf-8")):
        manifest += r.uri.encode("utf-8") + f"\t{r.size}\t{r.sha256}\n".encode("ascii")
    return hashlib.sha256(manifest).hexdigest()


def scene_id(path):
    """The scene id of the scene file at ``path`` (hashing it and the
    resources it references), without asking the daemon."""
    return scene_id_of_files(collect_scene_files(path)[1])


def iter_chunks(files, chunk_size=CHUNK_SIZE):
    """Yields the bytes of every file in order, each file cut into pieces of at
    most ``chunk_size`` bytes (a chunk never spans two files)."""
    for scene_file in files:
        with open(scene_file.path, "rb") as f:
            for chunk in iter(lambda: f.read(chunk_size), b""):
                yield chunk
