#!/usr/bin/env python3
"""Latency of /v1/status over naneyed's HTTPS, alone and with N stalled TLS handshakes held open.

Loopback only, bounded: 200 sequential requests per phase, each on a fresh connection (so each pays a
handshake), then N connections that send half a ClientHello (or nothing) and stall, then 200 more.
Usage: scripts/tls-load.py PORT TOKEN_FILE [N=400]. Give naneyed a head_timeout_ms longer than the
run (e.g. 60000) to keep the stalled connections open throughout the second phase.
"""
import socket
import ssl
import sys
import time

port, token = int(sys.argv[1]), open(sys.argv[2]).read().strip()
stalled_count = int(sys.argv[3]) if len(sys.argv) > 3 else 400
ctx = ssl.create_default_context()
ctx.check_hostname = False
ctx.verify_mode = ssl.CERT_NONE  # a self-signed test certificate
request = (f"GET /v1/status HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nAuthorization: Bearer {token}\r\n"
           "Connection: close\r\n\r\n").encode()


def one():
    t0 = time.perf_counter()
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        with ctx.wrap_socket(s, server_hostname="localhost") as t:
            t.sendall(request)
            data = b""
            while chunk := t.recv(65536):
                data += chunk
    if not data.startswith(b"HTTP/1.1 200"):
        raise SystemExit(f"unexpected answer: {data[:80]!r}")
    return (time.perf_counter() - t0) * 1000


def phase(name, n=200):
    lat = sorted(one() for _ in range(n))
    print(f"{name}: n={n} p50={lat[n // 2]:.2f} ms p99={lat[int(n * 0.99) - 1]:.2f} ms max={lat[-1]:.2f} ms")


phase("TLS, fresh connection each")
stalled = []
for i in range(stalled_count):
    s = socket.create_connection(("127.0.0.1", port))
    if i % 2 == 0:
        s.send(bytes([0x16, 3, 1, 2, 0, 1, 0, 1, 0xFC]))  # a ClientHello's first 9 bytes
    stalled.append(s)
phase(f"TLS, fresh connection each, {stalled_count} stalled handshakes open")
