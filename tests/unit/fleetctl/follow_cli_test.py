#!/usr/bin/env python3
"""`fleetctl follow` against a stand-in adapter on 127.0.0.1: exit 0 when it stops itself (--count
reached), 1 for a 401 (its message on stderr), for a closed port and for a stream that ends before
--count (it exited 0 on all three, so a script or a unit could not tell a failure); a stream that
ends names the --since that resumes it, and --since asks for the events after that id."""
import http.server
import socket
import subprocess
import sys
import threading
import time

def event(n):
    return b'id: %d\nevent: task\ndata: {"event_id": %d, "id": "t-%d", "state": "done"}\n\n' % (n, n, n)


class Handler(http.server.BaseHTTPRequestHandler):
    def do_GET(self):
        token = self.headers.get("Authorization")
        if token not in ("Bearer good", "Bearer short"):
            body = b'{"error": "unauthorized", "message": "a valid bearer token is required"}'
            self.send_response(401)
            self.send_header("Content-Type", "application/json")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)
            return
        self.send_response(200)
        self.send_header("Content-Type", "text/event-stream")
        self.end_headers()
        try:
            since = int(self.path.split("since=")[1]) if "since=" in self.path else 0
            self.wfile.write(b"".join(event(n) for n in range(since + 1, 3)))
            self.wfile.flush()
            # The token "short" ends the stream after two events; else keep-alives until the client goes.
            for _ in range(0 if token == "Bearer short" else 30):
                time.sleep(0.2)
                self.wfile.write(b": keep-alive\n\n")
                self.wfile.flush()
        except OSError:
            pass

    def log_message(self, *args):
        pass


class Server(http.server.ThreadingHTTPServer):
    daemon_threads = True


server = Server(("127.0.0.1", 0), Handler)
threading.Thread(target=server.serve_forever, daemon=True).start()
url = f"http://127.0.0.1:{server.server_address[1]}"
probe = socket.socket()
probe.bind(("127.0.0.1", 0))
closed = f"http://127.0.0.1:{probe.getsockname()[1]}"
probe.close()  # nothing listens there now


def follow(base, token, *args):
    return subprocess.run([sys.argv[1], "--url", base, "follow", *args], capture_output=True, text=True,
                          timeout=30, env={"FLEET_WMS_TOKEN": token})


failed = []
ok = follow(url, "good", "--count", "2")
if ok.returncode != 0 or ok.stdout.count('"t-') != 2:
    failed.append(f"--count 2 on a good stream: exit {ok.returncode} (want 0), stdout {ok.stdout!r}, {ok.stderr}")
denied = follow(url, "bad", "--count", "2")
if denied.returncode != 1 or "401" not in denied.stderr or "bearer token" not in denied.stderr:
    failed.append(f"401: exit {denied.returncode} (want 1), stderr {denied.stderr!r}")
gone = follow(closed, "good", "--count", "2")
if gone.returncode != 1 or "cannot reach" not in gone.stderr:
    failed.append(f"closed port: exit {gone.returncode} (want 1), stderr {gone.stderr!r}")
ended = follow(url, "short", "--count", "5")
if (ended.returncode != 1 or "ended" not in ended.stderr or "resume with --since 2" not in ended.stderr
        or ended.stdout.count('"t-') != 2):
    failed.append(f"stream ended after 2 of 5 events: exit {ended.returncode} (want 1), stderr {ended.stderr!r}")
resumed = follow(url, "good", "--since", "1", "--count", "1")
if resumed.returncode != 0 or resumed.stdout.count('"t-2"') != 1 or '"t-1"' in resumed.stdout:
    failed.append(f"--since 1: exit {resumed.returncode} (want 0), stdout {resumed.stdout!r}, {resumed.stderr}")
server.shutdown()
print("\n".join(failed) if failed else "ok")
sys.exit(1 if failed else 0)
