// Bad input to the bridge's front door: LCM URLs are checked before liblcm sees them (liblcm
// prints its own line and fails, or only warns about a bad ttl and goes on).
#include <gtest/gtest.h>

#include "bridge_support.hpp"
#include "csp/bridge/lcm_url.hpp"

namespace csp::bridge {
namespace {

std::string url_error(const std::string& url) {
  try {
    checked_lcm_url(url);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(BridgeInput, LcmUrlsAreCheckedBeforeLiblcm) {
  EXPECT_EQ(url_error(kDefaultLcmUrl), "");
  EXPECT_EQ(url_error("udpm://239.255.76.67:7667"), "");
  EXPECT_EQ(url_error("udpm://224.0.0.1:1?ttl=255&recv_buf_size=65536"), "");
  EXPECT_EQ(url_error("memq://"), "");
  EXPECT_NE(url_error("bogus://x").find("expected udpm://"), std::string::npos);
  EXPECT_NE(url_error("udpm://1.2.3.4:7667").find("not a multicast address"), std::string::npos);
  EXPECT_NE(url_error("udpm://240.0.0.1:7667").find("not a multicast address"), std::string::npos);
  EXPECT_NE(url_error("udpm://239.255.76.67:99999").find("port `99999`"), std::string::npos);
  EXPECT_NE(url_error("udpm://239.255.76.67").find("ADDRESS:PORT"), std::string::npos);
  EXPECT_NE(url_error("udpm://239.255.76.67:7667?ttl=abc").find("ttl `abc`"), std::string::npos);
  EXPECT_NE(url_error("udpm://239.255.76.67:7667?ttl=256").find("ttl `256`"), std::string::npos);
  EXPECT_NE(url_error("udpm://239.255.76.67:7667?tll=1").find("unknown option `tll`"), std::string::npos);
  EXPECT_NE(url_error("udpm://lcm.example:7667").find("not an IPv4 address"), std::string::npos);
}

// One line on stderr, nothing printed before it, exit code 2.
TEST(BridgeInput, ServeNamesABadUrlOnOneLine) {
  test::Process serve({CSP_EXECUTABLE, "serve", "--duration", "0.01", "--lcm-url", "udpm://239.255.76.67:7667?ttl=abc"},
                      test::temp_path("bad-url.out"));
  EXPECT_EQ(serve.wait(std::chrono::seconds(30)), 2);
  const std::string out = serve.output();
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_NE(out.find("ttl `abc`"), std::string::npos) << out;
  test::Process infinite({CSP_EXECUTABLE, "serve", "--duration", "0.01", "--lockstep-timeout", "inf"}, test::temp_path("inf.out"));
  EXPECT_EQ(infinite.wait(std::chrono::seconds(30)), 2);
  EXPECT_NE(infinite.output().find("--lockstep-timeout"), std::string::npos) << infinite.output();
}

}  // namespace
}  // namespace csp::bridge
