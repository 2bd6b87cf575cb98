// Shared test fixture: every sampling test talks to the process-wide Probe.
#pragma once

#include <gtest/gtest.h>

#include "probe.h"
#include "stats.h"

namespace luxel::sampling_test {

class SamplingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto probe = Probe::instance();
    ASSERT_TRUE(probe.is_ok()) << probe.status().to_string();
    probe_ = probe.value();
  }
  Probe& probe() { return *probe_; }

 private:
  Probe* probe_ = nullptr;
};

}  // namespace luxel::sampling_test

// `auto name = value of expr`, failing the test with the error otherwise.
#define ASSIGN_OR_FAIL(name, expr)                                          \
  auto name##_result = (expr);                                              \
  ASSERT_TRUE(name##_result.is_ok()) << name##_result.status().to_string(); \
  auto name = std::move(name##_result.value())
