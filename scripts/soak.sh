#!/bin/bash
# Soak (issue 13): naneyed replaying the bundled capture at 62 pairs/s for 30 minutes under mixed
# HTTP load, RSS and open descriptors sampled every 10 s. Prints one line per sample, then whether
# RSS and descriptors stayed flat, pairs dropped, and the request latencies per endpoint.
#
#   scripts/soak.sh [--naneyed build/daemon/naneyed] [--minutes 30] [--fps 62] [--csv FILE]
#
# The capture's recorded rate is read from the daemon itself (/v1/status fps, from the sensors'
# own clocks) in a short first run at speed=realtime; the soak then replays at speed=fps/rate, so
# "62 fps" is the rate pairs arrive at, whatever rate the capture was recorded at. Only 127.0.0.1 is
# contacted; the daemon is started and stopped by this script.
set -euo pipefail
cd "$(dirname "$0")/.."
exec python3 - "$@" <<'PY'
import argparse, http.client, json, os, re, signal, socket, statistics, subprocess, sys, threading, time

ap = argparse.ArgumentParser()
ap.add_argument("--naneyed", default="build/daemon/naneyed")
ap.add_argument("--config", default="config/naneyed.toml")
ap.add_argument("--capture", default="tests/data/sim-d3-mono/capture.raw")
ap.add_argument("--minutes", type=float, default=30.0)
ap.add_argument("--fps", type=float, default=62.0, help="pairs per second to replay at")
ap.add_argument("--sample-s", type=float, default=10.0, help="RSS/descriptor sampling period")
ap.add_argument("--csv", help="also write the samples here")
a = ap.parse_args()
HOST = "127.0.0.1"
capture = os.path.abspath(a.capture)

def start(speed):
    """naneyed on an ephemeral loopback port; returns (process, port) once it listens."""
    uri = f"file://{capture}?speed={speed}&loop=1"
    p = subprocess.Popen([a.naneyed, "--config", a.config, "--source", uri, "--listen", f"{HOST}:0",
                          "--log-level", "info"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    deadline = time.monotonic() + 30
    for line in p.stdout:
        m = re.search(r"listening on http://[0-9.]+:(\d+)/", line)
        if m:
            # keep draining the log so the daemon never blocks on a full pipe
            threading.Thread(target=lambda: [None for _ in p.stdout], daemon=True).start()
            return p, int(m.group(1))
        if time.monotonic() > deadline:
            break
    p.kill()
    sys.exit("naneyed did not start listening")

def get(port, path, timeout=5.0):
    c = http.client.HTTPConnection(HOST, port, timeout=timeout)
    try:
        c.request("GET", path)
        r = c.getresponse()
        return r.status, r.read()
    finally:
        c.close()

def status(port):
    code, body = get(port, "/v1/status")
    return json.loads(body) if code == 200 else None

def stop(p):
    p.send_signal(signal.SIGTERM)
    try:
        return p.wait(timeout=15)
    except subprocess.TimeoutExpired:
        p.kill()
        return None

# 1. The capture's rate as the daemon replays it at speed=realtime (pairs processed per second of
# wall time). Not the sensors' clock in /v1/status: a looping pass starts again at once, so a
# 12-pair capture plays 12 pairs per 11 recorded intervals.
p, port = start("realtime")
time.sleep(1.0)
s_a, t_a = status(port), time.monotonic()
time.sleep(4.0)
s_b, t_b = status(port), time.monotonic()
stop(p)
rate = (s_b["pairs"]["processed"] - s_a["pairs"]["processed"]) / (t_b - t_a) if s_a and s_b else 0
if not rate or rate <= 0:
    sys.exit("could not measure the capture's replay rate from /v1/status")
speed = a.fps / rate
print(f"capture {a.capture}: {rate:.2f} pairs/s at speed=realtime (sensor clock {s_b['fps']['left']:.2f} fps); "
      f"replaying at speed={speed:.4f} for {a.fps:g} pairs/s, {a.minutes:g} min", flush=True)

# 2. The soak.
p, port = start(f"{speed:.6f}")
pid = p.pid
done = threading.Event()
lock = threading.Lock()
lat = {}      # endpoint -> list of ms
fails = {}    # endpoint -> count
def record(name, ms, ok):
    with lock:
        if ok:
            lat.setdefault(name, []).append(ms)
        else:
            fails[name] = fails.get(name, 0) + 1

def keepalive_client(paths, period_s):
    """One keep-alive connection cycling through paths, a request every period_s; reconnects on error."""
    c, i = None, 0
    while not done.is_set():
        name = paths[i % len(paths)]
        i += 1
        t0 = time.monotonic()
        try:
            if c is None:
                c = http.client.HTTPConnection(HOST, port, timeout=5)
            c.request("GET", name)
            r = c.getresponse()
            r.read()
            record(name.split("?")[0], (time.monotonic() - t0) * 1000, r.status in (200, 422))
            if r.getheader("Connection", "").lower() == "close":
                c.close(); c = None
        except (OSError, http.client.HTTPException):
            record(name.split("?")[0], 0, False)
            if c: c.close()
            c = None
        done.wait(period_s)

def fresh_client(paths, period_s):
    """A fresh connection per request (accept/close churn: descriptors must come back)."""
    i = 0
    while not done.is_set():
        name = paths[i % len(paths)]
        i += 1
        t0 = time.monotonic()
        try:
            code, _ = get(port, name)
            record(name.split("?")[0] + " (fresh)", (time.monotonic() - t0) * 1000, code == 200)
        except (OSError, http.client.HTTPException):
            record(name.split("?")[0] + " (fresh)", 0, False)
        done.wait(period_s)

events_seen = [0]
def sse_client():
    """An event stream read continuously, reopened every 60 s (slots must come back)."""
    while not done.is_set():
        try:
            with socket.create_connection((HOST, port), timeout=5) as s:
                s.sendall(b"GET /v1/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
                t_end = time.monotonic() + 60
                while time.monotonic() < t_end and not done.is_set():
                    chunk = s.recv(65536)
                    if not chunk:
                        break
                    events_seen[0] += chunk.count(b"event: result")
        except OSError:
            record("/v1/events", 0, False)
            done.wait(1.0)

# About 45 requests/s in all: enough to keep every handler busy, little enough to leave the shared
# cores to the pipeline (the figure under test is flatness, not throughput).
threads = [
    threading.Thread(target=keepalive_client, args=(["/v1/status", "/metrics"], 0.1)),
    threading.Thread(target=keepalive_client, args=(["/v1/depth", "/v1/depth/at?u=125&v=110"], 0.05)),
    threading.Thread(target=keepalive_client, args=(["/v1/frames/left.png", "/v1/frames/right.png?overlay=1"], 0.5)),
    threading.Thread(target=fresh_client, args=(["/v1/status", "/v1/depth"], 0.2)),
    threading.Thread(target=sse_client),
]
for t in threads:
    t.daemon = True
    t.start()

def rss_kb():
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])

def fds():
    return len(os.listdir(f"/proc/{pid}/fd"))

def cpu_s():
    """naneyed's user + system CPU time, seconds (fields 14 and 15 of /proc/PID/stat)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

def load1():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])

def cpu_jiffies():
    """(steal, total) jiffies of all cores: on a VM, steal is the time its host took the cores."""
    with open("/proc/stat") as f:
        v = [int(x) for x in f.readline().split()[1:]]
    return v[7], sum(v[:8])

def steal_pct(j0, j1):
    """The share of the cores' time between two cpu_jiffies() readings that was steal, %."""
    return 100.0 * (j1[0] - j0[0]) / max(1, j1[1] - j0[1])

samples = []  # (t_s, rss_kb, fds, processed, dropped)
s0 = status(port)
t_start = time.monotonic()
csv = open(a.csv, "w") if a.csv else None
if csv:
    csv.write("t_s,rss_kb,fds,pairs_processed,pairs_dropped\n")
print(f"{'t_s':>6} {'rss_MB':>7} {'fds':>4} {'processed':>9} {'pairs/s':>7} {'dropped':>7} {'cpu_%':>5} {'load1':>5} {'steal%':>6}", flush=True)
cpu_prev, t_prev = cpu_s(), 0.0
jiffies_prev = jiffies_start = cpu_jiffies()
alive = True
while time.monotonic() - t_start < a.minutes * 60:
    time.sleep(a.sample_s)
    if p.poll() is not None:
        alive = False
        print(f"naneyed exited with {p.returncode}", flush=True)
        break
    try:
        st = status(port)
    except (OSError, http.client.HTTPException):
        st = None
    t = time.monotonic() - t_start
    proc = st["pairs"]["processed"] if st else -1
    drop = st["counters"]["pairs_dropped"] if st else -1
    rate_now = (proc - samples[-1][3]) / (t - samples[-1][0]) if samples and st else float("nan")
    samples.append((t, rss_kb(), fds(), proc, drop))
    cpu_now = cpu_s()
    cpu_pct = 100 * (cpu_now - cpu_prev) / (t - t_prev)
    cpu_prev, t_prev = cpu_now, t
    j = cpu_jiffies()
    steal = steal_pct(jiffies_prev, j)
    jiffies_prev = j
    print(f"{t:6.0f} {samples[-1][1] / 1024:7.1f} {samples[-1][2]:4d} {proc:9d} {rate_now:7.1f} {drop:7d} "
          f"{cpu_pct:5.1f} {load1():5.1f} {steal:6.1f}", flush=True)
    if csv:
        csv.write(",".join(str(x) for x in samples[-1]) + "\n"); csv.flush()

done.set()
s1 = status(port) if alive else None
if alive:
    stop(p)

# 3. Verdicts. Warm-up: the first minute (pools, the PNG encoder, httplib's threads reach their size).
steady = [s for s in samples if s[0] >= 60] or samples
third = max(1, len(steady) // 3)
first, last = steady[:third], steady[-third:]
rss_growth_mb = (max(s[1] for s in last) - max(s[1] for s in first)) / 1024
fd_growth = max(s[2] for s in last) - max(s[2] for s in first)
print(f"\nRSS after warm-up: min {min(s[1] for s in steady) / 1024:.1f} MB, max {max(s[1] for s in steady) / 1024:.1f} MB; "
      f"peak of the last third minus peak of the first third {rss_growth_mb:+.2f} MB")
print(f"descriptors after warm-up: min {min(s[2] for s in steady)}, max {max(s[2] for s in steady)}; "
      f"last third's peak minus first third's {fd_growth:+d}")
rss_flat = rss_growth_mb <= 1.0   # 1 MB: allocator noise; a leak of one pair's 125 kB per minute would exceed it
fd_flat = fd_growth <= 0
print(f"RSS flat: {rss_flat}   descriptors flat: {fd_flat}")
if s0 and s1:
    n = s1["pairs"]["processed"] - s0["pairs"]["processed"]
    wall = samples[-1][0] if samples else 1
    print(f"pairs processed {n} in {wall:.0f} s ({n / wall:.2f}/s); dropped "
          f"{s1['counters']['pairs_dropped'] - s0['counters']['pairs_dropped']} (source) "
          f"{s1['pairs']['dropped'] - s0['pairs']['dropped']} (pipeline); "
          f"capture-to-publish p50/p99/max {s1['capture_to_publish_ms']['p50']:.2f}/"
          f"{s1['capture_to_publish_ms']['p99']:.2f}/{s1['capture_to_publish_ms']['max']:.2f} ms (last 2048 pairs)")
print(f"events received {events_seen[0]}; the host took {steal_pct(jiffies_start, jiffies_prev):.1f} % of the cores (steal)")
print(f"{'endpoint':<28} {'requests':>8} {'failed':>6} {'p50_ms':>7} {'p99_ms':>7} {'max_ms':>7}")
for name in sorted(set(lat) | set(fails)):
    v = sorted(lat.get(name, []))
    q = lambda f: v[min(len(v) - 1, int(f * len(v)))] if v else float("nan")
    print(f"{name:<28} {len(v):8d} {fails.get(name, 0):6d} {q(0.5):7.2f} {q(0.99):7.2f} {v[-1] if v else float('nan'):7.2f}")
ok = alive and rss_flat and fd_flat and s1 is not None and s1["counters"]["pairs_dropped"] == s0["counters"]["pairs_dropped"]
print("alive", alive)
print("PASS" if ok else "FAIL")
sys.exit(0 if ok else 1)
PY
