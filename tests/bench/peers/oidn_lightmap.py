"""Intel Open Image Denoise on a baked lightmap, for blender_bake.py --denoise.

What a Blender user does with a noisy bake: run OIDN over the image. Through
OIDN's C API with ctypes (pyoidn needs cffi, which neither Debian's python3
nor the bpy venv has), on the CPU device, colour input only (a bake has no
albedo or normal pass), filter "RT" with hdr on (what 5.0.1's compositor
Denoise node runs; the only weights bpy 5.0.1's OIDN 2.3.3 ships: its
RTLightmap fails with "unsupported combination of input features") or
"RTLightmap" (OIDN's filter for HDR lightmaps, the one Luxel's own --denoise
oidn runs; LUXEL_OIDN_LIB=/opt/luxel/oidn/pyoidn/oidn/lib/libOpenImageDenoise.so.2,
Luxel's 2.5.1, worked inside bpy 5.0.1 beside Blender's 2.3.3).

The library: Blender's own, the one this process already loaded (bpy 5.0.1
ships OIDN 2.3.3 in bpy/lib for Cycles and the compositor), or
$LUXEL_OIDN_LIB. Debian's Blender 3.4.1 is built without OIDN, so its users
cannot denoise in Blender; loading another OIDN with its own TBB into it
aborts (munmap_chunk(): invalid pointer, Luxel's 2.5.1 from /opt/luxel
against Debian's TBB), so no other library is tried.
"""
import ctypes
import os

import numpy as np

DEVICE_TYPE_CPU = 1
FORMAT_FLOAT3 = 3
QUALITY_HIGH = 6


def candidates():
    """$LUXEL_OIDN_LIB, then libOpenImageDenoise.so.2 beside any OIDN
    library this process has mapped (Blender's own)"""
    paths = []
    if os.environ.get("LUXEL_OIDN_LIB"):
        paths.append(os.environ["LUXEL_OIDN_LIB"])
    with open("/proc/self/maps") as f:
        for line in f:
            lib = line.split()[-1]
            if "libOpenImageDenoise" in lib:
                p = os.path.join(os.path.dirname(lib), "libOpenImageDenoise.so.2")
                if p not in paths:
                    paths.append(p)
    return paths


class Oidn:
    """one CPU device, reused for every image"""

    def __init__(self):
        self.path = next((p for p in candidates() if os.path.isfile(p)), None)
        if self.path is None:
            raise SystemExit("--denoise: this Blender has no Open Image Denoise loaded (Debian's 3.4.1 "
                             "is built without it); LUXEL_OIDN_LIB=path names another, at your risk")
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

    def denoise(self, rgb, filter_type="RT"):
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
