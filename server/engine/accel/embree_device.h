// One process-wide Embree device, created on first use.
#pragma once

#include <embree3/rtcore.h>

#include "common/status.h"

namespace luxel::accel {

// The shared RTCDevice, or an error naming Embree's failure.
Result<RTCDevice> embree_device();

}  // namespace luxel::accel
