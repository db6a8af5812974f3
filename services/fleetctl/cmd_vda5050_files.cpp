// fleetctl vda5050-files: broker, ACL and bridge files for VDA 5050 vehicles.

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "vda5050_setup.hpp"

namespace fleet::ctl {

namespace {

struct FilesCommandOptions {
  Vda5050Files vf;
  std::string robots;
  std::string seenAt;
};

int writeFiles(FilesCommandOptions& o) {
  Vda5050Files& vf = o.vf;
  for (std::size_t at = 0; at <= o.robots.size();) {
    const std::size_t comma = std::min(o.robots.find(',', at), o.robots.size());
    if (comma > at) {
      vf.robots.push_back(o.robots.substr(at, comma - at));
    }
    at = comma + 1;
  }
  for (const auto& r : vf.robots) {
    if (r.find_first_of("/#+ ") != std::string::npos) {
      std::cerr
          << "fleetctl vda5050-files: robot id \"" << r
          << "\" cannot be a VDA 5050 serial number (no '/', '#', '+' or spaces in MQTT topic levels)\n";
      return 2;
    }
  }
  if (vf.robots.empty()) {
    std::cerr << "fleetctl vda5050-files: --robots names no robot\n";
    return 2;
  }
  if (!o.seenAt.empty()) {
    vf.seen_at = o.seenAt;
    vf.log_to_file = false;
  }
  std::error_code ec;
  std::filesystem::create_directories(vf.out, ec);
  if (auto written = writeVda5050Files(vf); !written) {
    std::cerr << "fleetctl vda5050-files: " << written.error().message << "\n";
    return 1;
  }
  std::cout << "fleetctl vda5050-files: " << vf.robots.size() << " vehicle(s) written to " << vf.out.string()
            << "\n";
  return 0;
}

}  // namespace

void addVda5050FilesCommand(CLI::App& app, Commands& commands) {
  auto* vdaFiles = app.add_subcommand(
      "vda5050-files",
      "write a Mosquitto configuration (listener, one password per vehicle, an ACL confining each to "
      "its topic subtree), the bridge's configuration and fleet-sim's vehicles file, e.g. for "
      "deploy/compose.vda5050.yaml");
  auto o = std::make_shared<FilesCommandOptions>();
  vdaFiles->add_option("dir", o->vf.out, "directory to write into (created)")->required();
  vdaFiles->add_option("--robots", o->robots, "robot ids that are VDA 5050 vehicles, comma-separated")
      ->required();
  vdaFiles->add_option("--map-id", o->vf.map_id, "the VDA 5050 mapId (the site's name)")->required();
  vdaFiles
      ->add_option("--broker-host", o->vf.broker_host,
                   "the broker's address as the bridge and vehicles reach it")
      ->capture_default_str();
  vdaFiles->add_option("--bind", o->vf.bind_address, "the broker's listening address")->capture_default_str();
  vdaFiles->add_option("--port", o->vf.port, "the broker's port")->required()->check(CLI::Range(1, 65535));
  vdaFiles->add_option("--seen-at", o->seenAt,
                       "the directory's path as the broker reads it (e.g. its mount point in a container); "
                       "the broker then logs to stderr");
  vdaFiles->add_flag("!--wall-clock", o->vf.sim_clock, "the bridge on the wall clock (default: lockstep)");
  commands.push_back({vdaFiles, [o] { return writeFiles(*o); }});
}

}  // namespace fleet::ctl
