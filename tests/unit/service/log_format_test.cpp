// JSON log escaping, request id cleaning and --metrics-listen checks, in
// process. The JSON side is judged by nlohmann::json's parser (strict about
// UTF-8), not by the code under test.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <random>

#include "service/log.h"
#include "service/metrics.h"
#include "service/rpc_interceptor.h"

namespace luxel::service {
namespace {

std::string parse_string(const std::string& quoted) {
  return nlohmann::json::parse(quoted).get<std::string>();
}

TEST(JsonQuote, ValidUtf8RoundTripsExactly) {
  const std::string s =
      "plain \"quoted\" back\\slash caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80 \x7f";
  EXPECT_EQ(parse_string(json_quote(s)), s);
}

TEST(JsonQuote, ControlCharactersAreEscapedOnOneLine) {
  std::string s;
  for (int c = 0; c < 0x20; ++c) s += static_cast<char>(c);
  const std::string q = json_quote(s);
  EXPECT_EQ(q.find('\n'), std::string::npos);
  EXPECT_EQ(q.find('\r'), std::string::npos);
  EXPECT_EQ(q.find('\0'), std::string::npos);
  EXPECT_EQ(parse_string(q), s);  // \u0000 etc. decode back to the same bytes
}

TEST(JsonQuote, InvalidUtf8BecomesReplacementCharacters) {
  const std::string fffd = "\xef\xbf\xbd";
  struct Case {
    std::string in, out;
  } cases[] = {
      {"a\xff"
       "b",
       "a" + fffd + "b"},
      {"\xc0\xaf", fffd + fffd},                        // overlong '/'
      {"\xed\xa0\x80", fffd + fffd + fffd},             // surrogate U+D800
      {"\xf4\x90\x80\x80", fffd + fffd + fffd + fffd},  // past U+10FFFF
      {"\xe2\x82", fffd + fffd},                        // truncated
      {"\x80", fffd},
  };
  for (const Case& c : cases) EXPECT_EQ(parse_string(json_quote(c.in)), c.out) << json_quote(c.in);
}

// Random byte strings: every one gives a parseable JSON string; where the
// input is valid UTF-8 without replacement it comes back unchanged.
TEST(JsonQuote, AnyByteStringParses) {
  std::mt19937 rng(7);
  for (int i = 0; i < 2000; ++i) {
    std::string s(rng() % 24, '\0');
    for (char& c : s) c = static_cast<char>(rng() & 0xff);
    const std::string q = json_quote(s);
    std::string back;
    ASSERT_NO_THROW(back = parse_string(q)) << q;
    if (back.find("\xef\xbf\xbd") == std::string::npos) EXPECT_EQ(back, s);
  }
}

TEST(RequestId, ClientValuesAreCleaned) {
  EXPECT_EQ(sanitize_request_id("abc-123_x.y:z"), "abc-123_x.y:z");
  using namespace std::string_literals;
  EXPECT_EQ(sanitize_request_id("a b\r\n\"c\"\x00\xff"
                                "d"s),
            "abcd");
  EXPECT_EQ(sanitize_request_id("\r\n \""), "");
  EXPECT_EQ(sanitize_request_id(std::string(100, 'z')).size(), 64u);
}

TEST(MetricsListen, AddressesAreChecked) {
  for (const char* ok : {"127.0.0.1:9464", "0.0.0.0:1", "[::1]:9464", "10.1.2.3:0"})
    EXPECT_TRUE(check_listen_address("--metrics-listen", ok).is_ok()) << ok;
  for (const char* bad :
       {"", "9464", ":9464", "127.0.0.1", "127.0.0.1:", "127.0.0.1:65536", "127.0.0.1:http",
        "localhost:9464", "1.2.3:80", "256.0.0.1:80", "[::1:80", "1.2.3.4.5:80"}) {
    const Status st = check_listen_address("--metrics-listen", bad);
    EXPECT_FALSE(st.is_ok()) << bad;
    EXPECT_NE(st.message().find("--metrics-listen: "), std::string::npos) << st.message();
  }
}

TEST(LogThrottle, OneLinePerPeriodWithTheCountHeldBack) {
  LogThrottle throttle(std::chrono::seconds(1));
  const auto t0 = LogThrottle::Clock::time_point() + std::chrono::hours(1);
  uint64_t held = 99;
  EXPECT_TRUE(throttle.admit(t0, &held));
  EXPECT_EQ(held, 0u);
  for (int i = 1; i <= 500; ++i)
    EXPECT_FALSE(throttle.admit(t0 + std::chrono::microseconds(i), &held));
  EXPECT_FALSE(throttle.admit(t0 + std::chrono::milliseconds(999), &held));
  EXPECT_TRUE(throttle.admit(t0 + std::chrono::seconds(1), &held));
  EXPECT_EQ(held, 501u);
  EXPECT_TRUE(throttle.admit(t0 + std::chrono::seconds(5), &held));
  EXPECT_EQ(held, 0u);
}

}  // namespace
}  // namespace luxel::service
