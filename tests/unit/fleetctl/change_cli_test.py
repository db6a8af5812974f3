#!/usr/bin/env python3
"""`fleetctl change` against a stand-in adapter on 127.0.0.1: PATCH /v1/tasks/ID with the body its
options make (--priority, --deadline as RFC 3339, --deadline-ns, --no-deadline), the adapter's
answer printed; exit 1 on a refusal (409) and, without anything to change, before any request."""
import http.server
import json
import subprocess
import sys
import threading

seen = []


class Handler(http.server.BaseHTTPRequestHandler):
    def do_PATCH(self):
        body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
        seen.append((self.path, body, self.headers.get("Authorization")))
        busy = self.path.endswith("/busy")
        out = (json.dumps({"error": "conflict", "state": "assigned", "message": "task 'busy' is assigned"}) if busy
               else json.dumps({"id": self.path.rsplit("/", 1)[1], "state": "queued", "changed": True, **body}))
        data = out.encode()
        self.send_response(409 if busy else 200)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)

    def log_message(self, *args):
        pass


server = http.server.HTTPServer(("127.0.0.1", 0), Handler)
threading.Thread(target=server.serve_forever, daemon=True).start()
url = f"http://127.0.0.1:{server.server_address[1]}"


def run(*args):
    return subprocess.run([sys.argv[1], "--url", url, "change", *args], capture_output=True, text=True, timeout=30,
                          env={"FLEET_WMS_TOKEN": "t"})


failed = []
cases = [
    (["job-1", "--priority", "50", "--deadline", "2026-12-02T14:05:00Z"], {"priority": 50, "deadline": "2026-12-02T14:05:00Z"}),
    (["job-2", "--deadline-ns", "123"], {"deadline_ns": 123}),
    (["job-3", "--no-deadline"], {"deadline_ns": 0}),
    (["job-4", "--priority", "-7"], {"priority": -7}),
]
for args, body in cases:
    before = len(seen)
    out = run(*args)
    if out.returncode != 0:
        failed.append(f"{args}: exit {out.returncode}: {out.stderr}")
    if len(seen) != before + 1 or seen[-1][0] != f"/v1/tasks/{args[0]}" or seen[-1][1] != body:
        failed.append(f"{args}: sent {seen[before:]}, expected PATCH /v1/tasks/{args[0]} {body}")
    elif seen[-1][2] != "Bearer t":
        failed.append(f"{args}: no bearer token")
    if '"changed": true' not in out.stdout:
        failed.append(f"{args}: the answer was not printed: {out.stdout}")
out = run("busy", "--priority", "1")
if out.returncode != 1 or '"state": "assigned"' not in out.stdout:
    failed.append(f"a 409: exit {out.returncode}, printed {out.stdout}")
before = len(seen)
out = run("job-5")
if out.returncode == 0 or len(seen) != before or "--priority" not in out.stderr:
    failed.append(f"nothing to change: exit {out.returncode}, {len(seen) - before} requests, {out.stderr}")
out = run("job-6", "--priority", "5000")
if out.returncode == 0 or len(seen) != before:
    failed.append(f"--priority 5000: exit {out.returncode}, sent {seen[before:]}")
out = run("job-7", "--deadline", "2026-12-02T14:05:00Z", "--no-deadline")
if out.returncode == 0 or len(seen) != before:
    failed.append(f"--deadline with --no-deadline: exit {out.returncode}")
server.shutdown()
print("\n".join(failed) if failed else "ok")
sys.exit(1 if failed else 0)
