// fleetctl's --url: strict, so a typo is refused rather than read as another address.

#include "url.hpp"

#include <gtest/gtest.h>

using fleet::ctl::parseUrl;

TEST(FleetctlUrl, ReadsHttpAndHttpsWithTheirDefaultPorts) {
  auto a = parseUrl("http://127.0.0.1:8080");
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(a->scheme, "http");
  EXPECT_EQ(a->host, "127.0.0.1");
  EXPECT_EQ(a->port, 8080);
  EXPECT_EQ(a->text(), "http://127.0.0.1:8080");
  EXPECT_EQ(parseUrl("https://wms.example")->port, 443);
  EXPECT_EQ(parseUrl("http://localhost/")->port, 80);
  auto v6 = parseUrl("http://[::1]:9000");
  ASSERT_TRUE(v6) << v6.error().message;
  EXPECT_EQ(v6->host, "::1");
  EXPECT_EQ(v6->text(), "http://[::1]:9000");
}

TEST(FleetctlUrl, RefusesWhatIsNotAnAddress) {
  for (const char* bad : {"http://localhost:80x80", "localhost:8080", "ftp://host", "http://", "http://:80",
                          "http://host:", "http://host:0", "http://host:65536", "http://host:8080/v1",
                          "http://user@host", "http://ho st", "http://[::1", "http://[::1]x"}) {
    auto r = parseUrl(bad);
    EXPECT_FALSE(r) << bad;
    if (!r) {
      EXPECT_NE(r.error().message.find(bad), std::string::npos) << r.error().message;
    }
  }
}
