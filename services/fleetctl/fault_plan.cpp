#include "fault_plan.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <tuple>

namespace fleet::ctl {
namespace {

/// A whole-string number; no sign, no trailing characters, finite.
bool number(const std::string& s, double& out) {
  if (s.empty()) {
    return false;
  }
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size() && std::isfinite(out) && out >= 0;
}

bool integer(const std::string& s, int& out) {
  if (s.empty()) {
    return false;
  }
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size() && out >= 0;
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

/// Splits "T[+D]" into the time and the optional down time (a trailing "s" is allowed on both).
Expected<std::pair<double, double>> timing(std::string s, double defaultDown, bool downRequired,
                                           double maxDown = 600, const std::string& unit = "wall seconds") {
  std::string down;
  if (const auto plus = s.find('+'); plus != std::string::npos) {
    down = s.substr(plus + 1);
    s = s.substr(0, plus);
  }
  auto strip = [](std::string& v) {
    if (!v.empty() && v.back() == 's') {
      v.pop_back();
    }
  };
  strip(s);
  strip(down);
  double at = 0;
  if (!number(s, at)) {
    return unexpected("invalid", "expected a time in simulated seconds >= 0 after '@', got \"" + s + "\"");
  }
  double d = defaultDown;
  if (down.empty() && downRequired) {
    return unexpected("invalid", "expected '+D' (how many " + unit + " it lasts) after the time");
  }
  if (!down.empty() && (!number(down, d) || d <= 0 || d > maxDown)) {
    return unexpected("invalid", "expected a duration in " + unit + " in (0, " + fmt(maxDown) +
                                     "] after '+', got \"" + down + "\"");
  }
  return std::make_pair(at, d);
}

Expected<Fault> parseOne(const std::string& spec) {
  Fault f;
  if (spec.rfind("drop-dds=", 0) == 0) {
    f.kind = Fault::Kind::DropDds;
    const std::string v = spec.substr(9);
    if (!number(v, f.fraction) || f.fraction <= 0 || f.fraction > 0.5) {
      return unexpected("invalid", "drop-dds: expected a fraction in (0, 0.5], got \"" + v + "\"");
    }
    return f;
  }
  const auto at = spec.find('@');
  if (at == std::string::npos) {
    return unexpected(
        "invalid",
        "expected kill-agent@T[+D][:K], kill-manager@T[+D], kill-traffic@T[+D], stall:ROBOT@T+D, "
        "hide-landmarks@T+D, close@T+D:X1,Y1,... or drop-dds=F");
  }
  const std::string head = spec.substr(0, at);
  std::string tail = spec.substr(at + 1);
  if (head == "kill-agent") {
    f.kind = Fault::Kind::KillAgent;
    if (const auto colon = tail.find(':'); colon != std::string::npos) {
      if (!integer(tail.substr(colon + 1), f.agent)) {
        return unexpected("invalid", "kill-agent: expected an agent process index >= 0 after ':', got \"" +
                                         tail.substr(colon + 1) + "\"");
      }
      tail = tail.substr(0, colon);
    }
    auto t = timing(tail, 2.0, false);
    if (!t) {
      return unexpected("invalid", "kill-agent: " + t.error().message);
    }
    std::tie(f.atS, f.downS) = *t;
    return f;
  }
  if (head == "kill-manager" || head == "kill-traffic") {
    f.kind = head == "kill-manager" ? Fault::Kind::KillManager : Fault::Kind::KillTraffic;
    auto t = timing(tail, 1.0, false);
    if (!t) {
      return unexpected("invalid", head + ": " + t.error().message);
    }
    std::tie(f.atS, f.downS) = *t;
    return f;
  }
  if (head.rfind("stall:", 0) == 0) {
    f.kind = Fault::Kind::StallRobot;
    f.robot = head.substr(6);
    if (f.robot.empty()) {
      return unexpected("invalid", "stall: expected a robot id after 'stall:'");
    }
    auto t = timing(tail, 0.0, true);
    if (!t) {
      return unexpected("invalid", "stall: " + t.error().message);
    }
    std::tie(f.atS, f.downS) = *t;
    return f;
  }
  if (head == "close") {
    f.kind = Fault::Kind::CloseArea;
    const auto colon = tail.find(':');
    if (colon == std::string::npos) {
      return unexpected("invalid",
                        "close: expected ':X1,Y1,X2,Y2,X3,Y3[,...]' (the area's corners) after T+D");
    }
    std::string corners = tail.substr(colon + 1);
    tail = tail.substr(0, colon);
    auto t = timing(tail, 0.0, true, 86400, "simulated seconds");
    if (!t) {
      return unexpected("invalid", "close: " + t.error().message);
    }
    std::tie(f.atS, f.downS) = *t;
    for (std::size_t pos = 0; pos <= corners.size();) {
      const auto comma = std::min(corners.find(',', pos), corners.size());
      const std::string v = corners.substr(pos, comma - pos);
      double x = 0;
      const bool negative = !v.empty() && v[0] == '-';
      if (!number(negative ? v.substr(1) : v, x)) {
        return unexpected("invalid", "close: expected a coordinate in m, got \"" + v + "\"");
      }
      f.area.push_back(negative ? -x : x);
      pos = comma + 1;
    }
    if (f.area.size() < 6 || f.area.size() % 2 != 0 || f.area.size() > 512) {
      return unexpected("invalid", "close: the area needs X,Y pairs of 3 to 256 corners");
    }
    return f;
  }
  if (head == "hide-landmarks") {
    f.kind = Fault::Kind::HideLandmarks;
    auto t = timing(tail, 0.0, true, 86400, "simulated seconds");
    if (!t) {
      return unexpected("invalid", "hide-landmarks: " + t.error().message);
    }
    std::tie(f.atS, f.downS) = *t;
    return f;
  }
  return unexpected("invalid",
                    "unknown fault \"" + head +
                        "\" (known: kill-agent, kill-manager, kill-traffic, stall:ROBOT, hide-landmarks, "
                        "close, drop-dds)");
}

}  // namespace

Expected<std::vector<Fault>> parseFaults(const std::vector<std::string>& specs) {
  std::vector<Fault> out;
  std::string problems;
  int drops = 0;
  for (const auto& s : specs) {
    auto f = parseOne(s);
    if (!f) {
      problems += (problems.empty() ? "" : "\n") + std::string("--fault \"") + s + "\": " + f.error().message;
      continue;
    }
    if (f->kind == Fault::Kind::DropDds && ++drops > 1) {
      problems += (problems.empty() ? "" : "\n") + std::string("--fault \"") + s +
                  "\": drop-dds given more than once";
      continue;
    }
    out.push_back(*f);
  }
  if (!problems.empty()) {
    return unexpected("invalid", problems);
  }
  return out;
}

std::string describe(const Fault& f) {
  switch (f.kind) {
    case Fault::Kind::KillAgent:
      return "kill-agent@" + fmt(f.atS) + "+" + fmt(f.downS) + ":" + std::to_string(f.agent);
    case Fault::Kind::KillManager:
      return "kill-manager@" + fmt(f.atS) + "+" + fmt(f.downS);
    case Fault::Kind::KillTraffic:
      return "kill-traffic@" + fmt(f.atS) + "+" + fmt(f.downS);
    case Fault::Kind::StallRobot:
      return "stall:" + f.robot + "@" + fmt(f.atS) + "+" + fmt(f.downS);
    case Fault::Kind::DropDds:
      return "drop-dds=" + fmt(f.fraction);
    case Fault::Kind::HideLandmarks:
      return "hide-landmarks@" + fmt(f.atS) + "+" + fmt(f.downS);
    case Fault::Kind::CloseArea: {
      std::string s = "close@" + fmt(f.atS) + "+" + fmt(f.downS) + ":";
      for (std::size_t i = 0; i < f.area.size(); ++i) {
        s += (i > 0 ? "," : "") + fmt(f.area[i]);
      }
      return s;
    }
  }
  return "";
}

std::string killedService(const Fault& f) {
  switch (f.kind) {
    case Fault::Kind::KillManager:
      return "fleet_manager";
    case Fault::Kind::KillTraffic:
      return "traffic_manager";
    default:
      return "";
  }
}

double dropFraction(const std::vector<Fault>& faults) {
  for (const auto& f : faults) {
    if (f.kind == Fault::Kind::DropDds) {
      return f.fraction;
    }
  }
  return 0.0;
}

}  // namespace fleet::ctl
