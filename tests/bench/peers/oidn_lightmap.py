"""Intel Open Image Denoise on a baked lightmap, for blender_bake.py --denoise.

What a Blender user does with a noisy bake: run OIDN over the image. Through
OIDN's C API with ctypes (pyoidn needs cffi, which neither Debian's python3
nor the bpy venv has), on the CPU device, colour input only (a bake has no
albedo or normal pass), filter "RTLightmap" (OIDN's filter for HDR
lightmaps, the one Luxel's own --denoise oidn runs) or "RT" with hdr on
(what 5.0.1's compositor Denoise node runs on a render).

The library: $LUXEL_OIDN_LIB, else the one inside the bpy module (5.0.1 ships
OIDN 2.3.3 for Cycles and the compositor), else Luxel's
(/opt/luxel/oidn from deploy/install-deps.sh: 2.5.1). Debian's Blender 3.4.1
is built without OIDN, so under it only Luxel's is found.
"""
import ctypes
import os

import numpy as np

DEVICE_TYPE_CPU = 1
FORMAT_FLOAT3 = 3
QUALITY_HIGH = 6


def candidates():
    paths = []
    if os.environ.get("LUXEL_OIDN_LIB"):
        paths.append(os.environ["LUXEL_OIDN_LIB"])
    try:
        import bpy
        paths.append(os.path.join(os.path.dirname(bpy.__file__), "lib", "libOpenImageDenoise.so.2"))
    except ImportError:
        pass
    prefix = os.environ.get("LUXEL_PREFIX", "/opt/luxel")
    paths.append(os.path.join(prefix, "oidn", "pyoidn", "oidn", "lib", "libOpenImageDenoise.so.2"))
    return paths


class Oidn:
    """one CPU device, reused for every image"""

    def __init__(self):
        self.path = next((p for p in candidates() if os.path.isfile(p)), None)
        if self.path is None:
            raise SystemExit("--denoise: no libOpenImageDenoise.so.2 among " + ", ".join(candidates()))
        lib = ctypes.CDLL(self.path)
        vp, cp = ctypes.c_void_p, ctypes.c_char_p
        lib.oidnNewDevice.restype = vp
        lib.oidnNewDevice.argtypes = [ctypes.c_int]
        lib.oidnCommitDevice.argtypes = [vp]
        lib.oidnGetDeviceInt.restype = ctypes.c_int
        lib.oidnGetDeviceInt.argtypes = [vp, cp]
        lib.oidnGetDeviceError.restype = ctypes.c_int
        lib.oidnGetDeviceError.argtypes = [vp, ctypes.POINTER(cp)]
        lib.oidnNewFilter.restype = vp
        lib.oidnNewFilter.argtypes = [vp, cp]
        lib.oidnSetSharedFilterImage.argtypes = [vp, cp, vp, ctypes.c_int, ctypes.c_size_t, ctypes.c_size_t,
                                                 ctypes.c_size_t, ctypes.c_size_t, ctypes.c_size_t]
        lib.oidnSetFilterBool.argtypes = [vp, cp, ctypes.c_bool]
        lib.oidnSetFilterInt.argtypes = [vp, cp, ctypes.c_int]
        for f in ("oidnCommitFilter", "oidnExecuteFilter", "oidnReleaseFilter"):
            getattr(lib, f).argtypes = [vp]
        self.lib = lib
        self.device = lib.oidnNewDevice(DEVICE_TYPE_CPU)
        lib.oidnCommitDevice(self.device)
        self.check("device")
        v = lib.oidnGetDeviceInt(self.device, b"version")
        self.version = f"{v // 10000}.{v // 100 % 100}.{v % 100}"

    def check(self, what):
        msg = ctypes.c_char_p()
        if self.lib.oidnGetDeviceError(self.device, ctypes.byref(msg)):
            raise RuntimeError(f"OIDN {what}: {msg.value.decode() if msg.value else 'error'}")

    def denoise(self, rgb, filter_type="RTLightmap"):
        """rgb: (h, w, 3) float32 -> a denoised copy"""
        src = np.ascontiguousarray(rgb, np.float32)
        dst = np.empty_like(src)
        h, w, _ = src.shape
        lib = self.lib
        flt = lib.oidnNewFilter(self.device, filter_type.encode())
        for name, img in ((b"color", src), (b"output", dst)):
            lib.oidnSetSharedFilterImage(flt, name, img.ctypes.data, FORMAT_FLOAT3, w, h, 0, 12, 12 * w)
        if filter_type == "RT":
            lib.oidnSetFilterBool(flt, b"hdr", True)
        lib.oidnSetFilterInt(flt, b"quality", QUALITY_HIGH)
        lib.oidnCommitFilter(flt)
        lib.oidnExecuteFilter(flt)
        lib.oidnReleaseFilter(flt)
        self.check(f"filter {filter_type}")
        return dst
