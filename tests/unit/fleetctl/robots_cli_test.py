#!/usr/bin/env python3
"""`fleetctl robots` against a stand-in adapter on 127.0.0.1: every robot of /v1/robots is printed
(it printed none while it iterated a member of a destroyed temporary), a robot without a pose is
printed with zeros, and an entry that is not an object is skipped without a crash."""
import http.server
import subprocess
import sys
import threading

BODY = (b'{"robots": [{"id": "r1", "pose": {"x": 12.5, "y": 3.25, "theta": 1.0}, "mode": "idle",'
        b' "battery": 0.8, "task": ""}, {"id": "r2", "mode": "busy", "task": "t-7"}, 42]}')


class Handler(http.server.BaseHTTPRequestHandler):
    def do_GET(self):
        ok = self.path == "/v1/robots"
        self.send_response(200 if ok else 404)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(BODY) if ok else 0))
        self.end_headers()
        if ok:
            self.wfile.write(BODY)

    def log_message(self, *args):
        pass


server = http.server.HTTPServer(("127.0.0.1", 0), Handler)
threading.Thread(target=server.serve_forever, daemon=True).start()
url = f"http://127.0.0.1:{server.server_address[1]}"
out = subprocess.run([sys.argv[1], "--url", url, "robots"], capture_output=True, text=True, timeout=30,
                     env={"FLEET_WMS_TOKEN": "t"})
server.shutdown()
lines = out.stdout.splitlines()
failed = []
if out.returncode != 0:
    failed.append(f"exit {out.returncode}: {out.stderr}")
if not any(l.startswith("r1") and "12.50" in l and "3.25" in l and "80%" in l for l in lines):
    failed.append("no line for r1 with its pose and battery")
if not any(l.startswith("r2") and "0.00" in l and "t-7" in l for l in lines):
    failed.append("no line for r2 (no pose: zeros)")
if len(lines) != 3:
    failed.append(f"expected a header and 2 robots, got {len(lines)} lines")
print("\n".join(failed) if failed else "ok")
print(out.stdout)
sys.exit(1 if failed else 0)
