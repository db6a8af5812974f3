#include "rfc3339.hpp"

#include <cstdio>
#include <ctime>

namespace fleet::wms {

std::string toRfc3339(std::int64_t unixNs) {
  constexpr std::int64_t kNs = 1'000'000'000;
  std::int64_t s = unixNs / kNs;
  std::int64_t frac = unixNs % kNs;
  if (frac < 0) {
    frac += kNs;
    --s;
  }
  const auto t = static_cast<std::time_t>(s);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  const auto n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  std::string out(buf, n);
  if (frac != 0) {
    char f[16];
    if (frac % 1'000'000 == 0) {
      std::snprintf(f, sizeof f, ".%03lld", static_cast<long long>(frac / 1'000'000));
    } else if (frac % 1000 == 0) {
      std::snprintf(f, sizeof f, ".%06lld", static_cast<long long>(frac / 1000));
    } else {
      std::snprintf(f, sizeof f, ".%09lld", static_cast<long long>(frac));
    }
    out += f;
  }
  return out + "Z";
}

namespace {

bool digits(const std::string& t, std::size_t at, std::size_t n, int& out) {
  if (at + n > t.size()) {
    return false;
  }
  out = 0;
  for (std::size_t i = at; i < at + n; ++i) {
    if (t[i] < '0' || t[i] > '9') {
      return false;
    }
    out = out * 10 + (t[i] - '0');
  }
  return true;
}

bool leap(int y) {
  return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
}

/// Days from 1970-01-01 to y-m-d (proleptic Gregorian; Howard Hinnant's days_from_civil).
std::int64_t daysFromCivil(int y, int m, int d) {
  y -= m <= 2 ? 1 : 0;
  const int era = (y >= 0 ? y : y - 399) / 400;
  const int yoe = y - era * 400;
  const int doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const int doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return static_cast<std::int64_t>(era) * 146097 + doe - 719468;
}

}  // namespace

std::optional<std::int64_t> parseRfc3339(const std::string& t, std::string* why) {
  auto fail = [&](const std::string& w) -> std::optional<std::int64_t> {
    if (why != nullptr) {
      *why = w;
    }
    return std::nullopt;
  };
  const std::string form =
      "expected an RFC 3339 time such as \"2026-12-02T14:05:00Z\" or \"2026-12-02T15:05:00.250+01:00\"";
  int y = 0, mo = 0, d = 0, h = 0, mi = 0, s = 0;
  if (t.size() > 40 || !digits(t, 0, 4, y) || t.size() < 19 || t[4] != '-' || !digits(t, 5, 2, mo) ||
      t[7] != '-' || !digits(t, 8, 2, d) || (t[10] != 'T' && t[10] != 't' && t[10] != ' ') ||
      !digits(t, 11, 2, h) || t[13] != ':' || !digits(t, 14, 2, mi) || t[16] != ':' || !digits(t, 17, 2, s)) {
    return fail(form);
  }
  static constexpr int kDays[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (mo < 1 || mo > 12 || d < 1 || d > kDays[mo - 1] + (mo == 2 && leap(y) ? 1 : 0) || h > 23 || mi > 59 ||
      s > 60) {
    return fail("\"" + t + "\": a date or time field out of range");
  }
  s = s == 60 ? 59 : s;  // a leap second is read as the second before it
  std::size_t i = 19;
  std::int64_t frac = 0;
  if (i < t.size() && t[i] == '.') {
    ++i;
    std::size_t n = 0;
    while (i < t.size() && t[i] >= '0' && t[i] <= '9') {
      if (n < 9) {
        frac = frac * 10 + (t[i] - '0');
      }
      ++n;
      ++i;
    }
    if (n == 0 || n > 9) {
      return fail("\"" + t + "\": the fraction of a second needs 1 to 9 digits");
    }
    for (; n < 9; ++n) {
      frac *= 10;
    }
  }
  std::int64_t offsetS = 0;
  if (i < t.size() && (t[i] == 'Z' || t[i] == 'z')) {
    ++i;
  } else if (i < t.size() && (t[i] == '+' || t[i] == '-')) {
    int oh = 0, om = 0;
    if (!digits(t, i + 1, 2, oh) || i + 3 >= t.size() || t[i + 3] != ':' || !digits(t, i + 4, 2, om) ||
        oh > 23 || om > 59) {
      return fail("\"" + t + "\": the offset must be Z or +HH:MM / -HH:MM");
    }
    offsetS = (t[i] == '+' ? 1 : -1) * (oh * 3600 + om * 60);
    i += 6;
  } else {
    return fail("\"" + t + "\": no offset (Z or +HH:MM): " + form);
  }
  if (i != t.size()) {
    return fail(form);
  }
  const std::int64_t secs = daysFromCivil(y, mo, d) * 86400 + h * 3600 + mi * 60 + s - offsetS;
  // int64 ns reach 2262-04-11; times before 1970 are no use to a fleet (ns 0 means "none").
  if (secs < 0 || secs > 9'223'372'035) {
    return fail("\"" + t + "\": outside 1970-01-01 .. 2262-04-11");
  }
  return secs * 1'000'000'000 + frac;
}

}  // namespace fleet::wms
