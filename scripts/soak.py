#!/usr/bin/env python3
"""Hostile soak: the release service on loopback under a mix of good requests, bad
inputs, slow clients, hang-ups and overload bursts, for a bounded time.

Checks: no 5xx but 503/504; the same photo with the same ends always gives the same
cables; the server's resident memory at the end within 1.5x of its level after the
first minute. Prints a summary and exits non-zero on a failed check.

    python3 scripts/soak.py --binary target/release/ariadne --minutes 10

Standard library only. Reads photos from $ARIADNE_DATASET (default
../shared/datasets/cables).
"""

import argparse
import collections
import http.client
import json
import os
import random
import socket
import subprocess
import sys
import threading
import time
import urllib.parse

DATASET = os.environ.get("ARIADNE_DATASET", "../shared/datasets/cables")


def terminals(txt_path, width=640, height=480, tol=12.0):
    ends = []
    with open(txt_path) as f:
        for line in f:
            v = line.split()
            if not v:
                continue
            k = int(v[0])
            pts = [(float(v[1 + 2 * j]), float(v[2 + 2 * j])) for j in range(k)]
            for x, y in (pts[0], pts[-1]):
                if tol <= x <= width - 1 - tol and tol <= y <= height - 1 - tol:
                    ends.append([x, y])
    return ends


class Soak:
    def __init__(self, port, photos):
        self.port = port
        self.photos = photos  # [(jpeg bytes, ends)]
        self.statuses = collections.Counter()
        self.failures = []
        self.answers = {}  # photo index -> cables signature
        self.lock = threading.Lock()

    def note(self, kind, status):
        with self.lock:
            self.statuses[f"{kind} {status}"] += 1
            if status >= 500 and status not in (503, 504):
                self.failures.append(f"{kind}: {status}")

    def request(self, method, path, body=b"", headers=None, timeout=30):
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=timeout)
        try:
            conn.request(method, path, body=body, headers=headers or {})
            response = conn.getresponse()
            return response.status, response.read()
        finally:
            conn.close()

    def good(self, rng):
        i = rng.randrange(len(self.photos))
        jpeg, ends = self.photos[i]
        query = urllib.parse.urlencode({"endpoints": json.dumps(ends)})
        status, body = self.request("POST", f"/segment?{query}", jpeg,
                                    {"Content-Type": "image/jpeg"})
        self.note("good", status)
        if status == 200:
            cables = json.loads(body)["cables"]
            signature = json.dumps([c["polyline"] for c in cables])
            with self.lock:
                first = self.answers.setdefault(i, signature)
                if first != signature:
                    self.failures.append(f"photo {i}: different cables from the same input")

    def bad(self, rng):
        jpeg, _ = self.photos[rng.randrange(len(self.photos))]
        cases = [
            (b"", "image/jpeg", ""),
            (bytes(rng.randrange(256) for _ in range(3000)), "image/jpeg", ""),
            (jpeg[: len(jpeg) // 2], "image/jpeg", ""),
            (jpeg, "text/plain", ""),
            (jpeg, "image/jpegfoo", ""),
            (jpeg, "image/jpeg", "?endpoints=" + urllib.parse.quote("[[1e308, 2]]")),
            (jpeg, "image/jpeg", "?endpoints=" + urllib.parse.quote("[[1,2],")),
            (jpeg, "image/jpeg", "?preset=nope"),
            (jpeg, "image/jpeg", "?endpoints=" + urllib.parse.quote(json.dumps([[5, 5]] * 300))),
        ]
        body, content_type, query = rng.choice(cases)
        status, _ = self.request("POST", f"/segment{query}", body, {"Content-Type": content_type})
        self.note("bad", status)

    def slow(self, rng):
        """Headers dripped one byte at a time until the server cuts the connection."""
        s = socket.create_connection(("127.0.0.1", self.port), timeout=30)
        try:
            s.sendall(b"POST /segment HTTP/1.1\r\nHost: x\r\n")
            for _ in range(60):
                s.sendall(b"a")
                time.sleep(0.5)
        except OSError:
            pass  # cut by the server: what should happen
        finally:
            s.close()
        with self.lock:
            self.statuses["slow cut"] += 1

    def hang_up(self, rng):
        jpeg, ends = self.photos[rng.randrange(len(self.photos))]
        s = socket.create_connection(("127.0.0.1", self.port), timeout=30)
        query = urllib.parse.urlencode({"endpoints": json.dumps(ends)})
        s.sendall(f"POST /segment?{query} HTTP/1.1\r\nHost: x\r\nContent-Type: image/jpeg\r\n"
                  f"Content-Length: {len(jpeg)}\r\n\r\n".encode() + jpeg)
        time.sleep(rng.uniform(0.0, 0.1))
        s.close()
        with self.lock:
            self.statuses["hang-up"] += 1

    def burst(self, rng):
        threads = [threading.Thread(target=self.good, args=(random.Random(rng.random()),))
                   for _ in range(24)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()


def rss_kb(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--binary", default="target/release/ariadne")
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--port", type=int, default=18181)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    names = sorted(n[:-4] for n in os.listdir(f"{DATASET}/simple") if n.endswith(".jpg"))
    photos = []
    for n in names[::4]:
        with open(f"{DATASET}/simple/{n}.jpg", "rb") as f:
            photos.append((f.read(), terminals(f"{DATASET}/simple/{n}.txt")))
    server = subprocess.Popen(
        [args.binary, "serve", "--bind", f"127.0.0.1:{args.port}", "--header-timeout-s", "5",
         "--body-timeout-s", "10"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    soak = Soak(args.port, photos)
    try:
        for _ in range(300):
            try:
                if soak.request("GET", "/readyz", timeout=2)[0] == 200:
                    break
            except OSError:
                pass
            time.sleep(0.2)
        end = time.time() + args.minutes * 60
        rss, stop = [], threading.Event()

        def sample():
            while not stop.is_set():
                rss.append((time.time(), rss_kb(server.pid)))
                stop.wait(5)

        def loop(kind, seed):
            rng = random.Random(seed)
            while time.time() < end:
                try:
                    getattr(soak, kind)(rng)
                except OSError as e:
                    with soak.lock:
                        soak.statuses[f"{kind} {type(e).__name__}"] += 1
                if kind == "burst":
                    time.sleep(20)

        threads = [threading.Thread(target=sample)]
        for i, kind in enumerate(["good", "good", "bad", "slow", "slow", "hang_up", "burst"]):
            threads.append(threading.Thread(target=loop, args=(kind, args.seed + i)))
        for t in threads:
            t.start()
        for t in threads[1:]:
            t.join()
        stop.set()
        threads[0].join()
        alive = server.poll() is None
    finally:
        server.terminate()
        server.wait(timeout=60)
    start = time.time() - args.minutes * 60
    settled = [kb for t, kb in rss if t >= start + 60] or [kb for _, kb in rss]
    first, last = settled[0], rss[-1][1]
    print(f"{args.minutes:g} min, {sum(soak.statuses.values())} exchanges")
    for key, count in sorted(soak.statuses.items()):
        print(f"  {key}: {count}")
    print(f"RSS: {first / 1024:.0f} MB after the first minute, {last / 1024:.0f} MB at the end, "
          f"{max(kb for _, kb in rss) / 1024:.0f} MB at most")
    ok = alive and not soak.failures and last <= 1.5 * first
    for failure in soak.failures[:20]:
        print("FAIL", failure)
    if not alive:
        print("FAIL the server died")
    if last > 1.5 * first:
        print("FAIL memory grew over 1.5x")
    print("OK" if ok else "FAILED")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
