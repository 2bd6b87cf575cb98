// The OpenCL context of a test: the default device (device::Context::create():
// PoCL on a CPU-only machine), either one per test executable or one per test
// suite.
#pragma once

#include <gtest/gtest.h>

#include "device/context.h"

namespace luxel::testing {

// One context for the whole test executable (PoCL start-up and program loads
// are paid once), created on first use. Aborts with the status when there is
// no device: helpers that call it have no test to fail.
device::Context& shared_context();

// A test suite with its own context: created before the suite's first test
// (a fatal failure of the suite when there is no device), released after its
// last. Base is ::testing::Test or a ::testing::TestWithParam<T>. A suite
// that sets up more calls ASSERT_NO_FATAL_FAILURE(DeviceTest::SetUpTestSuite())
// first and DeviceTest::TearDownTestSuite() last.
template <typename Base = ::testing::Test>
class DeviceTest : public Base {
 protected:
  static void SetUpTestSuite() {
    auto ctx = device::Context::create();
    ASSERT_TRUE(ctx) << ctx.status().to_string();
    ctx_ = std::move(ctx.value()).release();
  }
  static void TearDownTestSuite() {
    delete ctx_;
    ctx_ = nullptr;
  }

  static inline device::Context* ctx_ = nullptr;
};

}  // namespace luxel::testing
