// The part of Intel Open Image Denoise's C API (oidn.h, OIDN 2.x) that
// post/oidn.cpp calls, declared here from the API documentation
// (openimagedenoise.org, "Open Image Denoise API": "Devices", "Filters",
// "RTLightmap") because Luxel loads the library at run time (dlopen) instead
// of linking it: Debian 12 has no package, and a machine without it must still
// bake with the a-trous filter. Only function-pointer types are declared, so no
// symbol here can be linked by accident.
#pragma once

#include <cstddef>

namespace luxel::pipeline::oidn {

// Opaque handles ("Devices", "Filters": reference-counted objects).
struct DeviceImpl;
struct FilterImpl;
using Device = DeviceImpl*;
using Filter = FilterImpl*;

// OIDNDeviceType: the CPU device is the one every x86-64 build ships.
enum DeviceType : int { kDeviceDefault = 0, kDeviceCpu = 1 };

// OIDNError: what oidnGetDeviceError returns (0: none).
enum Error : int {
  kErrorNone = 0,
  kErrorUnknown = 1,
  kErrorInvalidArgument = 2,
  kErrorInvalidOperation = 3,
  kErrorOutOfMemory = 4,
  kErrorUnsupportedHardware = 5,
  kErrorCancelled = 6,
};

// OIDNFormat: RTLightmap's "color" and "output" are FLOAT3 images.
enum Format : int { kFormatUndefined = 0, kFormatFloat = 1, kFormatFloat3 = 3 };

// The C entry points (all extern "C" in oidn.h), as pointer types.
using NewDeviceFn = Device (*)(DeviceType type);
using CommitDeviceFn = void (*)(Device device);
using GetDeviceErrorFn = Error (*)(Device device, const char** out_message);
using GetDeviceIntFn = int (*)(Device device, const char* name);
using SetDeviceIntFn = void (*)(Device device, const char* name, int value);
using ReleaseDeviceFn = void (*)(Device device);
using NewFilterFn = Filter (*)(Device device, const char* type);
// "Images": a host pointer the filter reads (or writes) in place; strides 0
// mean tightly packed.
using SetSharedFilterImageFn = void (*)(Filter filter, const char* name, void* dev_ptr,
                                        Format format, size_t width, size_t height,
                                        size_t byte_offset, size_t pixel_byte_stride,
                                        size_t row_byte_stride);
using SetFilterBoolFn = void (*)(Filter filter, const char* name, bool value);
using CommitFilterFn = void (*)(Filter filter);
using ExecuteFilterFn = void (*)(Filter filter);
using ReleaseFilterFn = void (*)(Filter filter);

}  // namespace luxel::pipeline::oidn
