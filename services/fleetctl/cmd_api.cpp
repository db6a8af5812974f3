// fleetctl's commands on the WMS adapter's HTTP API: submit, tasks, task, change, cancel, pause,
// resume, robots, close, reopen, closures, follow, health and metrics, and the options --url, --ca-cert and
// --token-file they reach the adapter with.

#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "fleet/core/bounded_file.hpp"
#include "task_file.hpp"
#include "url.hpp"

using nlohmann::json;

namespace fleet::ctl {

namespace {

// The options of the API commands: bound when they are declared, read when one runs.
struct ApiOptions {
  std::string url = "http://127.0.0.1:8080";
  std::string caCert;
  std::string tokenFile;
  std::string file;  // submit
  int batch = 500;
  std::string state;  // tasks
  int limit = 100;
  std::string id;               // task, change, cancel, pause, resume, close, reopen
  std::optional<int> priority;  // change
  std::string deadline;         // change: RFC 3339
  std::optional<std::int64_t> deadlineNs;
  bool noDeadline = false;
  std::vector<double> closeArea;
  std::vector<int> closeNodes;
  std::vector<std::string> closeLanes;
  std::string closeReason;
  int count = 0;  // follow
  int seconds = 0;
  std::int64_t since = -1;  // follow: resume after this event id (-1: from the next event)
};

struct Target {
  Url url;
  std::string token;
};

httplib::Headers headers(const Target& t) {
  if (t.token.empty()) {
    return {};
  }
  return {{"Authorization", "Bearer " + t.token}};
}

int fail(const std::string& msg) {
  std::fprintf(stderr, "fleetctl: %s\n", msg.c_str());
  return 1;
}

int show(const httplib::Result& r) {
  if (!r) {
    return fail("cannot reach the WMS adapter (" + httplib::to_string(r.error()) + ")");
  }
  auto j = json::parse(r->body, nullptr, false);
  std::cout << (j.is_discarded() ? r->body : j.dump(2)) << "\n";
  return r->status < 300 ? 0 : 1;
}

// One API command's work with the client to the adapter and the request headers; returns the exit code.
using Call = std::function<int(const ApiOptions&, httplib::Client&, const httplib::Headers&)>;

// Reaches the adapter as --url, --ca-cert and --token-file say, then calls: exit 2 for a bad --url
// or a --ca-cert without https, 1 for an unreadable token.
int withClient(const ApiOptions& o, const Call& call) {
  Target t;
  if (auto u = parseUrl(o.url)) {
    t.url = *u;
  } else {
    std::fprintf(stderr, "fleetctl: %s\n", u.error().message.c_str());
    return 2;
  }
  if (!o.tokenFile.empty()) {
    auto text = fleet::readBoundedFile(o.tokenFile, fleet::kTokenFileLimit, "token_file");
    if (!text) {
      return fail("cannot read a token: " + text.error().message);
    }
    t.token = text->substr(0, text->find('\n'));
    if (!t.token.empty() && t.token.back() == '\r') {
      t.token.pop_back();
    }
    if (t.token.empty()) {
      return fail("cannot read a token from " + o.tokenFile + ": the first line is empty");
    }
  } else if (const char* env = std::getenv("FLEET_WMS_TOKEN")) {
    t.token = env;
  }
  // https works when cpp-httplib is built with OpenSSL (Debian's is: CPPHTTPLIB_OPENSSL_SUPPORT).
  httplib::Client c(t.url.text());
  if (!o.caCert.empty()) {
    if (t.url.scheme != "https") {
      std::fprintf(stderr, "fleetctl: --ca-cert goes with an https:// --url\n");
      return 2;
    }
    c.set_ca_cert_path(o.caCert);
  }
  c.set_read_timeout(30, 0);
  const auto h = headers(t);
  return call(o, c, h);
}

int submitTasks(const ApiOptions& o, httplib::Client& c, const httplib::Headers& h) {
  auto all = loadTaskFile(o.file);
  if (!all) {
    return fail(all.error().message);
  }
  int ok = 0;
  int bad = 0;
  for (std::size_t i = 0; i < all->size(); i += static_cast<std::size_t>(o.batch)) {
    json part = json::array();
    for (std::size_t k = i; k < std::min(all->size(), i + static_cast<std::size_t>(o.batch)); ++k) {
      part.push_back((*all)[k]);
    }
    auto r = c.Post("/v1/tasks", h, part.dump(), "application/json");
    if (!r) {
      return fail("cannot reach the WMS adapter at " + o.url + " (" + httplib::to_string(r.error()) + ")");
    }
    auto body = json::parse(r->body, nullptr, false);
    if (body.is_object() && body.contains("results")) {
      for (const auto& item : body["results"]) {
        const int s = item.value("status", 0);
        if (s == 200 || s == 201) {
          ++ok;
        } else {
          ++bad;
          std::cerr << "fleetctl: " << item.dump() << "\n";
        }
      }
    } else {
      bad += static_cast<int>(part.size());
      std::cerr << "fleetctl: HTTP " << r->status << ": " << r->body << "\n";
    }
  }
  std::printf("submitted %d tasks, %d refused\n", ok, bad);
  return bad == 0 ? 0 : 1;
}

int listTasks(const ApiOptions& o, httplib::Client& c, const httplib::Headers& h) {
  std::string path = "/v1/tasks?limit=" + std::to_string(o.limit);
  if (!o.state.empty()) {
    path += "&state=" + o.state;
  }
  auto r = c.Get(path, h);
  if (!r || r->status != 200) {
    return show(r);
  }
  auto body = json::parse(r->body);
  // ETA: when the manager expects the task done (RFC 3339, UTC); "-" without an estimate.
  std::printf("%-24s %-11s %-12s %-24s %s\n", "ID", "STATE", "ROBOT", "ETA", "REASON");
  for (const auto& x : body["tasks"]) {
    std::printf("%-24s %-11s %-12s %-24s %s\n", x.value("id", "").c_str(), x.value("state", "").c_str(),
                x.value("robot", "").c_str(), x.value("eta", "-").c_str(), x.value("reason", "").c_str());
  }
  return 0;
}

int closeRoadmap(const ApiOptions& o, httplib::Client& c, const httplib::Headers& h) {
  json body = json::object();
  if (!o.closeArea.empty()) {
    if (o.closeArea.size() % 2 != 0 || o.closeArea.size() < 6) {
      std::fprintf(stderr, "fleetctl close: --area takes X,Y pairs of at least 3 corners\n");
      return 2;
    }
    body["area"] = json::array();
    for (std::size_t i = 0; i + 1 < o.closeArea.size(); i += 2) {
      body["area"].push_back({o.closeArea[i], o.closeArea[i + 1]});
    }
  }
  if (!o.closeNodes.empty()) {
    body["nodes"] = o.closeNodes;
  }
  for (const auto& l : o.closeLanes) {
    const auto colon = l.find(':');
    int from = 0;
    int to = 0;
    if (colon == std::string::npos || std::sscanf(l.c_str(), "%d:%d", &from, &to) != 2) {
      std::fprintf(stderr, "fleetctl close: --lane \"%s\": expected FROM:TO (two node ids)\n", l.c_str());
      return 2;
    }
    body["lanes"].push_back({from, to});
  }
  if (!o.closeReason.empty()) {
    body["reason"] = o.closeReason;
  }
  return show(c.Put("/v1/traffic/closures/" + o.id, h, body.dump(), "application/json"));
}

int listRobots(const ApiOptions&, httplib::Client& c, const httplib::Headers& h) {
  auto r = c.Get("/v1/robots", h);
  if (!r || r->status != 200) {
    return show(r);
  }
  std::printf("%-12s %8s %8s %7s %-9s %7s %s\n", "ID", "X", "Y", "THETA", "MODE", "BATTERY", "TASK");
  // The parsed body must outlive the loop (a range over a member of a temporary reads freed memory).
  const auto body = json::parse(r->body, nullptr, false);
  const auto robots = body.is_object() ? body.value("robots", json::array()) : json::array();
  for (const auto& x : robots) {
    if (!x.is_object()) {
      continue;
    }
    const auto pose = x.value("pose", json::object());
    std::printf("%-12s %8.2f %8.2f %7.2f %-9s %6.0f%% %s\n", x.value("id", "").c_str(), pose.value("x", 0.0),
                pose.value("y", 0.0), pose.value("theta", 0.0), x.value("mode", "").c_str(),
                100.0 * x.value("battery", 0.0), x.value("task", "").c_str());
  }
  return 0;
}

// Exit 0 only when it stopped itself (--count reached, --seconds up); 1 when the adapter cannot be
// reached, answers other than 200 (401, 403, 410 expired, 503 busy, ...), or the stream breaks or
// ends: then stderr names the --since that resumes after the last event printed.
int followEvents(const ApiOptions& o, httplib::Client& c, const httplib::Headers& h) {
  int seen = 0;
  std::int64_t lastId = o.since;  // the newest `id:` printed
  const auto start = std::chrono::steady_clock::now();
  std::string buf;
  int status = 0;
  std::string refusal;  // the body of an answer other than 200, bounded
  bool stopped = false;
  auto r = c.Get(
      o.since >= 0 ? "/v1/events?since=" + std::to_string(o.since) : std::string("/v1/events"), h,
      [&](const httplib::Response& res) {
        status = res.status;
        return true;
      },
      [&](const char* data, std::size_t n) {
        if (status != 200) {
          if (refusal.size() < 4096) {
            refusal.append(data, std::min(n, 4096 - refusal.size()));
          }
          return true;
        }
        buf.append(data, n);
        std::size_t pos = 0;
        while ((pos = buf.find("\n\n")) != std::string::npos) {
          const std::string frame = buf.substr(0, pos);
          buf.erase(0, pos + 2);
          if (frame.rfind("id: ", 0) == 0 || frame.find("\nid: ") != std::string::npos) {
            const auto at = frame.rfind("id: ", 0) == 0 ? 4 : frame.find("\nid: ") + 5;
            lastId = std::strtoll(frame.c_str() + at, nullptr, 10);
          }
          const auto d = frame.find("data: ");
          if (d != std::string::npos) {
            std::cout << frame.substr(d + 6) << std::endl;
            ++seen;
          }
        }
        const bool timeUp =
            o.seconds > 0 && std::chrono::steady_clock::now() - start > std::chrono::seconds(o.seconds);
        stopped = (o.count > 0 && seen >= o.count) || timeUp;
        return !stopped;
      });
  if (stopped) {
    return 0;
  }
  const std::string resume =
      lastId >= 0 ? "; resume with --since " + std::to_string(lastId) + " (nothing after it is missed)" : "";
  if (status != 0 && status != 200) {
    const auto j = json::parse(refusal, nullptr, false);
    const std::string why = j.is_object() && j.contains("message") && j["message"].is_string()
                                ? j["message"].get<std::string>()
                                : refusal.substr(0, refusal.find('\n'));
    return fail("the WMS adapter at " + o.url + " answered " + std::to_string(status) +
                (why.empty() ? std::string() : ": " + why) + (status == 410 ? std::string() : resume));
  }
  if (status == 0) {
    return fail("cannot reach the WMS adapter at " + o.url + " (" + httplib::to_string(r.error()) + ")" +
                resume);
  }
  if (!r) {
    return fail("the event stream from " + o.url + " broke (" + httplib::to_string(r.error()) + ")" + resume);
  }
  return fail("the event stream from " + o.url + " ended (the adapter closed it)" + resume);
}

}  // namespace

void addApiCommands(CLI::App& app, Commands& commands) {
  auto o = std::make_shared<ApiOptions>();
  app.add_option("--url", o->url, "WMS adapter address, http[s]://HOST[:PORT]")->envname("FLEET_WMS_URL");
  app.add_option("--ca-cert", o->caCert,
                 "https: PEM file of the CA that signed the adapter's certificate (else the system's)")
      ->envname("FLEET_WMS_CA_CERT");
  app.add_option("--token-file", o->tokenFile, "file holding the bearer token (else FLEET_WMS_TOKEN)");

  auto* submit = app.add_subcommand("submit", "submit tasks from a JSON or CSV file");
  submit->add_option("file", o->file, "tasks.json or tasks.csv")->required();
  submit->add_option("--batch", o->batch, "tasks per request")->check(CLI::Range(1, 1000));
  auto* tasks = app.add_subcommand("tasks", "list tasks");
  tasks->add_option("--state", o->state, "queued, assigned, en_route, ..., done, failed, cancelled");
  tasks->add_option("--limit", o->limit)->check(CLI::Range(1, 100000));
  auto* task = app.add_subcommand("task", "show one task");
  task->add_option("id", o->id)->required();
  auto* change = app.add_subcommand(
      "change",
      "change a waiting task's priority and/or deadline (PATCH /v1/tasks/ID); assigned ones are refused");
  change->add_option("id", o->id)->required();
  change->add_option("--priority", o->priority, "the new priority, higher first")
      ->check(CLI::Range(-1000, 1000));
  auto* dl =
      change->add_option("--deadline", o->deadline, "the new deadline as RFC 3339, 2026-12-02T14:05:00Z");
  auto* dlNs = change->add_option("--deadline-ns", o->deadlineNs, "the new deadline in ns of the fleet clock")
                   ->check(CLI::NonNegativeNumber);
  auto* none = change->add_flag("--no-deadline", o->noDeadline, "take the deadline away");
  dl->excludes(dlNs)->excludes(none);
  dlNs->excludes(none);
  auto* cancel = app.add_subcommand("cancel", "cancel a task");
  cancel->add_option("id", o->id)->required();
  auto* pause = app.add_subcommand(
      "pause", "hold a task: its robot stands still with it, a waiting task is not dispatched");
  pause->add_option("id", o->id)->required();
  auto* resume = app.add_subcommand("resume", "let a paused task go on");
  resume->add_option("id", o->id)->required();
  auto* robots = app.add_subcommand("robots", "list robots");
  auto* close = app.add_subcommand(
      "close", "close part of the roadmap to traffic (an area, nodes or lanes): robots are planned round it");
  close->add_option("id", o->id, "closure id (closing again under it replaces the closure)")->required();
  close->add_option("--area", o->closeArea, "polygon corners X1,Y1,X2,Y2,X3,Y3,... (m, map frame)")
      ->delimiter(',');
  close->add_option("--nodes", o->closeNodes, "roadmap node ids N1,N2,...")->delimiter(',');
  close->add_option("--lane", o->closeLanes,
                    "a directed roadmap edge FROM:TO (repeat; give both ways for both)");
  close->add_option("--reason", o->closeReason,
                    "why (shown with the closure and in the traffic manager's log)");
  auto* reopen = app.add_subcommand("reopen", "reopen a closure");
  reopen->add_option("id", o->id)->required();
  auto* closures = app.add_subcommand("closures", "list the roadmap closures in force");
  auto* follow = app.add_subcommand("follow", "print task events as they happen");
  follow->add_option("--count", o->count, "stop after this many events (0 = never)");
  follow->add_option("--seconds", o->seconds, "stop after this long (0 = never)");
  follow
      ->add_option("--since", o->since,
                   "print the events after this event id first (the id a broken follow names), then new ones")
      ->check(CLI::NonNegativeNumber);
  auto* health = app.add_subcommand("health", "is the adapter up and does it see the manager");
  auto* metrics = app.add_subcommand("metrics", "the adapter's counters");

  const auto add = [&commands, o](CLI::App* sub, Call call) {
    commands.push_back({sub, [o, call = std::move(call)] { return withClient(*o, call); }});
  };
  using Client = httplib::Client;
  using Headers = httplib::Headers;
  add(submit, submitTasks);
  add(tasks, listTasks);
  add(task,
      [](const ApiOptions& a, Client& c, const Headers& h) { return show(c.Get("/v1/tasks/" + a.id, h)); });
  add(change, [](const ApiOptions& a, Client& c, const Headers& h) {
    json body = json::object();
    if (a.priority) {
      body["priority"] = *a.priority;
    }
    if (!a.deadline.empty()) {
      body["deadline"] = a.deadline;
    } else if (a.deadlineNs) {
      body["deadline_ns"] = *a.deadlineNs;
    } else if (a.noDeadline) {
      body["deadline_ns"] = 0;
    }
    if (body.empty()) {
      return fail("change: give --priority, --deadline, --deadline-ns or --no-deadline");
    }
    return show(c.Patch("/v1/tasks/" + a.id, h, body.dump(), "application/json"));
  });
  add(cancel, [](const ApiOptions& a, Client& c, const Headers& h) {
    return show(c.Delete("/v1/tasks/" + a.id, h));
  });
  add(pause, [](const ApiOptions& a, Client& c, const Headers& h) {
    return show(c.Post("/v1/tasks/" + a.id + "/pause", h, "", "application/json"));
  });
  add(resume, [](const ApiOptions& a, Client& c, const Headers& h) {
    return show(c.Post("/v1/tasks/" + a.id + "/resume", h, "", "application/json"));
  });
  add(robots, listRobots);
  add(close, closeRoadmap);
  add(reopen, [](const ApiOptions& a, Client& c, const Headers& h) {
    return show(c.Delete("/v1/traffic/closures/" + a.id, h));
  });
  add(closures,
      [](const ApiOptions&, Client& c, const Headers& h) { return show(c.Get("/v1/traffic/closures", h)); });
  add(follow, followEvents);
  add(health, [](const ApiOptions&, Client& c, const Headers& h) { return show(c.Get("/v1/health", h)); });
  add(metrics, [](const ApiOptions&, Client& c, const Headers& h) { return show(c.Get("/v1/metrics", h)); });
}

}  // namespace fleet::ctl
