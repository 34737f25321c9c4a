#!/usr/bin/env python3
"""Static file server for the Spherical Faces web build (Python standard library only).

    python3 www/serve.py --root target/dist [--port 8080] [--host 127.0.0.1] [--allow-remote] [--quiet]

Serves DIR with the MIME types the app needs (application/wasm for .wasm, ...) and the
cross-origin isolation headers SharedArrayBuffer needs (COOP same-origin, COEP require-corp).
Only GET and HEAD; any path that resolves outside DIR (.., %2e%2e, symlinks, absolute paths) is
answered 403. Binds 127.0.0.1 by default and refuses non-loopback hosts without --allow-remote.
--port 0 picks a free port; the real URL is printed. Ctrl-C / SIGTERM stop it with exit code 0.
"""

import argparse
import errno
import ipaddress
import os
import shutil
import signal
import socket
import sys
from email.utils import formatdate
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import unquote

MIME_TYPES = {
    ".wasm": "application/wasm",
    ".js": "text/javascript; charset=utf-8",
    ".mjs": "text/javascript; charset=utf-8",
    ".html": "text/html; charset=utf-8",
    ".htm": "text/html; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json",
    ".map": "application/json",
    ".glb": "model/gltf-binary",
    ".gltf": "model/gltf+json",
    ".obj": "text/plain; charset=utf-8",
    ".txt": "text/plain; charset=utf-8",
    ".png": "image/png",
    ".jpg": "image/jpeg",
    ".jpeg": "image/jpeg",
    ".svg": "image/svg+xml",
    ".ico": "image/x-icon",
    ".woff2": "font/woff2",
}
DEFAULT_MIME = "application/octet-stream"

COMMON_HEADERS = (
    ("Cross-Origin-Opener-Policy", "same-origin"),
    ("Cross-Origin-Embedder-Policy", "require-corp"),
    ("Cross-Origin-Resource-Policy", "same-origin"),
    ("Cache-Control", "no-cache"),
    ("X-Content-Type-Options", "nosniff"),
)


class Forbidden(Exception):
    pass


def resolve_request_path(root, target):
    """Map a request target to a real file system path inside root, or raise Forbidden.

    root must already be a realpath. Returns the resolved path (which may not exist)."""
    if not target.startswith("/"):
        # absolute-form ("http://host/x") or garbage: we only serve origin-form targets
        raise Forbidden("request target must start with /")
    path = target.split("?", 1)[0].split("#", 1)[0]
    try:
        decoded = unquote(path, encoding="utf-8", errors="strict")
    except UnicodeDecodeError:
        raise Forbidden("path is not valid UTF-8")
    if "\x00" in decoded or "\\" in decoded:
        raise Forbidden("forbidden character in path")
    segments = [s for s in decoded.split("/") if s not in ("", ".")]
    if any(s == ".." for s in segments):
        raise Forbidden("'..' in path")
    resolved = os.path.realpath(os.path.join(root, *segments))
    if resolved != root and not resolved.startswith(root + os.sep):
        raise Forbidden("path resolves outside the served directory")
    return resolved


class Handler(BaseHTTPRequestHandler):
    server_version = "SphericalFacesServe/1.0"
    protocol_version = "HTTP/1.1"

    # set on the class by make_handler()
    root = "."
    quiet = False

    def version_string(self):
        return self.server_version

    def end_headers(self):
        for name, value in COMMON_HEADERS:
            self.send_header(name, value)
        super().end_headers()

    def log_message(self, format, *args):  # noqa: A002 - signature from the base class
        if not self.quiet:
            sys.stderr.write("%s - %s\n" % (self.address_string(), format % args))

    def do_GET(self):
        self.serve(send_body=True)

    def do_HEAD(self):
        self.serve(send_body=False)

    def method_not_allowed(self):
        self.send_response(HTTPStatus.METHOD_NOT_ALLOWED)
        self.send_header("Allow", "GET, HEAD")
        self.send_header("Content-Type", "text/plain; charset=utf-8")
        body = b"405 Method Not Allowed: only GET and HEAD\n"
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Connection", "close")
        self.close_connection = True
        self.end_headers()
        self.wfile.write(body)

    do_POST = do_PUT = do_DELETE = do_PATCH = do_OPTIONS = do_TRACE = do_CONNECT = method_not_allowed

    def send_plain(self, status, text, send_body=True):
        body = ("%d %s\n" % (status, text)).encode("utf-8")
        self.send_response(status)
        self.send_header("Content-Type", "text/plain; charset=utf-8")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if send_body:
            self.wfile.write(body)

    def serve(self, send_body):
        try:
            fs_path = resolve_request_path(self.root, self.path)
        except Forbidden as e:
            self.send_plain(HTTPStatus.FORBIDDEN, "Forbidden: %s" % e, send_body)
            return
        if os.path.isdir(fs_path):
            raw_path = self.path.split("?", 1)[0].split("#", 1)[0]
            if not raw_path.endswith("/"):
                query = self.path[len(raw_path):]
                self.send_response(HTTPStatus.MOVED_PERMANENTLY)
                self.send_header("Location", raw_path + "/" + query)
                self.send_header("Content-Length", "0")
                self.end_headers()
                return
            fs_path = os.path.join(fs_path, "index.html")
            # index.html itself could be a symlink pointing out
            fs_path = os.path.realpath(fs_path)
            if not fs_path.startswith(self.root + os.sep):
                self.send_plain(HTTPStatus.FORBIDDEN, "Forbidden", send_body)
                return
        if not os.path.isfile(fs_path):
            self.send_plain(HTTPStatus.NOT_FOUND, "Not Found", send_body)
            return
        try:
            f = open(fs_path, "rb")
        except OSError:
            self.send_plain(HTTPStatus.FORBIDDEN, "Forbidden", send_body)
            return
        with f:
            st = os.fstat(f.fileno())
            ext = os.path.splitext(fs_path)[1].lower()
            self.send_response(HTTPStatus.OK)
            self.send_header("Content-Type", MIME_TYPES.get(ext, DEFAULT_MIME))
            self.send_header("Content-Length", str(st.st_size))
            self.send_header("Last-Modified", formatdate(st.st_mtime, usegmt=True))
            self.end_headers()
            if send_body:
                shutil.copyfileobj(f, self.wfile, 1 << 20)


class Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = True  # on Linux this still refuses a port that has a listener

    def handle_error(self, request, client_address):
        exc = sys.exc_info()[1]
        if isinstance(exc, (ConnectionError, TimeoutError)):
            return  # client went away: not worth a traceback
        super().handle_error(request, client_address)


def is_loopback(host):
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        pass
    try:  # a host name: every address it resolves to must be loopback
        infos = socket.getaddrinfo(host, None)
    except socket.gaierror:
        return False
    return bool(infos) and all(ipaddress.ip_address(i[4][0].split("%")[0]).is_loopback for i in infos)


def fail(message, code=1):
    sys.stderr.write("serve.py: error: %s\n" % message)
    sys.exit(code)


def on_signal(signum, frame):
    raise KeyboardInterrupt()


def main(argv=None):
    # SIGTERM behaves like Ctrl-C: leave serve_forever(), close the socket, exit 0.
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    parser = argparse.ArgumentParser(description="Serve the Spherical Faces web build.")
    parser.add_argument("--root", required=True, help="directory to serve (e.g. target/dist)")
    parser.add_argument("--port", type=int, default=8080, help="port (0 picks a free one; default 8080)")
    parser.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    parser.add_argument("--allow-remote", action="store_true",
                        help="allow binding a non-loopback address (serves DIR to the network)")
    parser.add_argument("--quiet", action="store_true", help="do not log requests")
    args = parser.parse_args(argv)

    if not 0 <= args.port <= 65535:
        fail("port must be between 0 and 65535, got %d" % args.port, 2)
    root = os.path.realpath(args.root)
    if not os.path.isdir(root):
        fail("--root %s is not a directory (build first: bash www/dev.sh build)" % args.root, 2)
    host = args.host
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    if not args.allow_remote and not is_loopback(host):
        fail("refusing to serve on non-loopback host %s; pass --allow-remote to expose it to the network"
             % args.host, 2)

    handler = type("BoundHandler", (Handler,), {"root": root, "quiet": args.quiet})
    server_cls = Server
    if ":" in host:
        server_cls = type("Server6", (Server,), {"address_family": socket.AF_INET6})
    try:
        server = server_cls((host, args.port), handler)
    except OSError as e:
        if e.errno == errno.EADDRINUSE:
            fail("port %d on %s is already in use (stop the other server or pass --port N; --port 0 picks a free one)"
                 % (args.port, args.host))
        if e.errno == errno.EACCES:
            fail("permission denied binding %s:%d (ports below 1024 need privileges)" % (args.host, args.port))
        fail("cannot bind %s:%d: %s" % (args.host, args.port, e.strerror or e))

    port = server.server_address[1]
    url_host = "[%s]" % host if ":" in host else host
    try:
        print("Spherical Faces is being served at http://%s:%d/ (Ctrl-C to stop)" % (url_host, port), flush=True)
        server.serve_forever()
    except KeyboardInterrupt:  # SIGINT or SIGTERM (see on_signal)
        pass
    finally:
        # ignore a second Ctrl-C while closing
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        server.server_close()
    sys.stderr.write("Stopped.\n")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # a signal before serving started
        sys.exit(0)
