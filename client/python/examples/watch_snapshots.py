#!/usr/bin/python3
"""The editor-plugin pattern: upload a scene, submit a bake, write every
progressive snapshot the daemon streams to a folder (snapshot_0001.png, ...)
while printing progress, then download the finished lightmap.

    PYTHONPATH=client/python:build/python /usr/bin/python3 \
        client/python/examples/watch_snapshots.py scenes/cornell_box.gltf \
        --out /tmp/cornell --resolution 128 --samples 256

A plugin would swap the PNG files for a texture upload into its viewport.
Exit status: 0 when the bake succeeded and every artifact verified, 1 otherwise.
"""

import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))  # client/python

from luxel_client import Client, LuxelError, luxel_pb2, state_name  # noqa: E402

_EXTENSIONS = {luxel_pb2.SNAPSHOT_FORMAT_PNG: "png", luxel_pb2.SNAPSHOT_FORMAT_EXR: "exr",
               luxel_pb2.SNAPSHOT_FORMAT_UNSPECIFIED: "png"}


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", help=".gltf (with its external files beside it) or .glb")
    p.add_argument("--server", default="127.0.0.1:50051", help="luxeld host:port")
    p.add_argument("--token", default=None, help="bearer token, when the daemon requires one")
    p.add_argument("--tls-ca", default=None, help="PEM CA certificate: connect with TLS")
    p.add_argument("--out", default="luxel_out", help="folder for snapshots and results")
    p.add_argument("--samples", type=int, default=128, help="samples per texel")
    p.add_argument("--resolution", type=int, default=256, help="lightmap side in texels")
    p.add_argument("--snapshot-interval", type=float, default=1.0, help="seconds between snapshots")
    p.add_argument("--snapshot-format", choices=["png", "exr"], default="png")
    return p.parse_args(argv)


def describe(progress):
    eta = f"{progress.eta_s:6.1f} s" if progress.eta_s >= 0 else "     ?  "
    return (f"{100 * progress.fraction:5.1f} %  spp {progress.mean_spp:8.1f} (min {progress.min_spp})"
            f"  error {progress.error:.4f}  ETA {eta}")


class SnapshotWriter:
    """Receives BakeEvents; writes each snapshot image as it arrives."""

    def __init__(self, folder):
        self.folder = folder
        self.count = 0

    def __call__(self, event):
        info = event.info
        has_image = event.HasField("snapshot") and bool(event.snapshot.data)
        progress = info.progress
        if has_image and event.snapshot.progress.mean_spp > progress.mean_spp:
            progress = event.snapshot.progress  # the image can be newer than the last progress tick
        line = f"[{state_name(info.state):>11}] {describe(progress)}"
        if has_image:
            self.count += 1
            snap = event.snapshot
            name = f"snapshot_{self.count:04d}.{_EXTENSIONS.get(snap.format, 'bin')}"
            (self.folder / name).write_bytes(snap.data)
            line += f"  -> {name} ({snap.width}x{snap.height}, spp {snap.progress.mean_spp:.1f})"
        print(line, flush=True)


def main(argv=None):
    args = parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    writer = SnapshotWriter(out)
    try:
        with Client(args.server, token=args.token, tls_ca=args.tls_ca) as luxel:
            scene = luxel.upload_scene(args.scene)
            stats = scene.statistics
            print(f"scene {scene.scene_id[:12]} {scene.name}: {stats.triangles} triangles"
                  f"{' (already stored)' if scene.already_stored else ''}")
            for warning in scene.warnings:
                print(f"  warning: {warning}")
            bake = luxel.submit_bake(scene.scene_id, resolution=args.resolution,
                                     samples_per_texel=args.samples,
                                     snapshot_interval_s=args.snapshot_interval,
                                     snapshot_format=args.snapshot_format)
            print(f"bake {bake.bake_id} submitted")
            info = luxel.wait(bake.bake_id, on_event=writer)
            if state_name(info.state) != "SUCCEEDED":
                print(f"bake ended {state_name(info.state)}: {info.error_message}", file=sys.stderr)
                return 1
            print(f"done in {info.progress.elapsed_s:.2f} s ({info.termination}); "
                  f"{writer.count} snapshots; features: {info.features}")
            for artifact in info.artifacts:
                got = luxel.download(info.bake_id, artifact, out / artifact)
                print(f"  {got.path} {got.size} bytes sha256 {got.sha256[:16]}… verified")
    except LuxelError as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
