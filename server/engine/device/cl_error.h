// OpenCL error names and Status conversion.
#pragma once

#include <CL/cl.h>

#include <string>

#include "common/status.h"

namespace luxel::device {

// "CL_OUT_OF_RESOURCES" etc.; "CL_UNKNOWN_ERROR(<code>)" for unknown codes.
std::string cl_error_name(cl_int err);

// OK for CL_SUCCESS, otherwise a Status "<what>: CL_...". Allocation failures
// map to kResourceExhausted, the rest to kUnavailable (the driver failed us).
Status cl_status(cl_int err, const std::string& what);

}  // namespace luxel::device

#define LUXEL_CL_RETURN_IF_ERROR(call, what)                                             \
  do {                                                                                   \
    const cl_int _luxel_err = (call);                                                    \
    if (_luxel_err != CL_SUCCESS) return ::luxel::device::cl_status(_luxel_err, (what)); \
  } while (0)
