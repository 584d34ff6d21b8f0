#!/usr/bin/env python3
"""procfit's static file server for development and tests.

- Binds 127.0.0.1 only.
- Sends COOP `same-origin` and COEP `require-corp` on every response (also errors), so the page
  is cross-origin isolated and SharedArrayBuffer (threaded wasm) works. `--no-isolation` leaves
  them out, to exercise the page's single-threaded fallback.
- Correct MIME types for .wasm, .js/.mjs, .glb and friends.
- Compression by Accept-Encoding: a precompressed `FILE.br` or `FILE.gz` beside the file (what
  `make dist` writes) is sent as is when the client takes it and it is not older than the file;
  otherwise text, JavaScript, wasm and glTF are gzipped on the fly (kept in memory by path,
  size and mtime). `Vary: Accept-Encoding` on those replies.
- Refuses anything outside its root: `..` segments (also percent-encoded), absolute or
  protocol-relative paths, backslashes, NUL bytes and symlinks that lead out → 403; a missing
  file → 404.

Usage: serve.py [--root DIR] [--port N] [--no-isolation]   (PORT env var also works; 0 = any
free port). Prints the URL on its first line of stdout.
"""

import argparse
import errno
import gzip
import http.server
import os
import posixpath
import sys
import urllib.parse

MIME = {
    ".html": "text/html; charset=utf-8",
    ".js": "text/javascript; charset=utf-8",
    ".mjs": "text/javascript; charset=utf-8",
    ".css": "text/css; charset=utf-8",
    ".json": "application/json",
    ".wasm": "application/wasm",
    ".glb": "model/gltf-binary",
    ".gltf": "model/gltf+json",
    ".png": "image/png",
    ".jpg": "image/jpeg",
    ".jpeg": "image/jpeg",
    ".webp": "image/webp",
    ".svg": "image/svg+xml",
    ".ico": "image/x-icon",
    ".txt": "text/plain; charset=utf-8",
    ".md": "text/plain; charset=utf-8",
}


# Worth compressing: text formats, wasm and glTF (images are compressed already).
COMPRESSIBLE = {".html", ".js", ".mjs", ".css", ".json", ".wasm", ".glb", ".gltf", ".svg", ".txt", ".md"}
# Precompressed siblings, best first.
PRECOMPRESSED = (("br", ".br"), ("gzip", ".gz"))


def accepted_encodings(header):
    """The content codings an Accept-Encoding header takes (q > 0), lower-case."""
    out = set()
    for item in (header or "").split(","):
        name, _, params = item.strip().partition(";")
        q = 1.0
        for param in params.split(";"):
            key, _, value = param.strip().partition("=")
            if key == "q":
                try:
                    q = float(value)
                except ValueError:
                    q = 0.0
        if name and q > 0:
            out.add(name.strip().lower())
    if "*" in out:
        out |= {"br", "gzip"}
    return out


class Handler(http.server.BaseHTTPRequestHandler):
    root = "."
    isolation = True
    server_version = "procfit-serve"
    # On-the-fly gzip results: path -> ((size, mtime), bytes).
    gzipped = {}

    def log_message(self, fmt, *args):  # quiet by default; errors still reach stderr
        if os.environ.get("PROCFIT_SERVE_LOG"):
            super().log_message(fmt, *args)

    def send_common_headers(self):
        if self.isolation:
            self.send_header("Cross-Origin-Opener-Policy", "same-origin")
            self.send_header("Cross-Origin-Embedder-Policy", "require-corp")
        self.send_header("Cross-Origin-Resource-Policy", "same-origin")
        self.send_header("Cache-Control", "no-cache")
        self.send_header("X-Content-Type-Options", "nosniff")

    def fail(self, code, message):
        body = f"{code} {message}\n".encode()
        self.send_response(code)
        self.send_common_headers()
        self.send_header("Content-Type", "text/plain; charset=utf-8")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def send_error(self, code, message=None, explain=None):
        # http.server's own replies (501 unknown method, 414 long URI, 431 many headers, 400)
        # would go out without the isolation headers: route them through fail().
        self.close_connection = True
        self.fail(code, message or self.responses.get(code, ("error",))[0])

    def resolve(self):
        """Maps the request path to a file under root, or returns an HTTP error code."""
        raw = self.path.split("?", 1)[0].split("#", 1)[0]
        if not raw.startswith("/") or raw.startswith("//"):
            return 403
        path = urllib.parse.unquote(raw)
        if "\x00" in path or "\\" in path:
            return 403
        segments = path.split("/")
        if any(s in ("..", ".") for s in segments) or path.startswith("//"):
            return 403
        rel = posixpath.normpath(path).lstrip("/")
        full = os.path.join(self.root, rel)
        real = os.path.realpath(full)
        if real != self.root and not real.startswith(self.root + os.sep):
            return 403
        if os.path.isdir(real):
            real = os.path.join(real, "index.html")
        if not os.path.isfile(real):
            return 404
        return real

    def do_HEAD(self):
        self.do_GET()

    def do_GET(self):
        target = self.resolve()
        if isinstance(target, int):
            self.fail(target, "Forbidden" if target == 403 else "Not Found")
            return
        ext = os.path.splitext(target)[1].lower()
        try:
            encoding, body = self.encoded(target, ext)
        except OSError:
            self.fail(404, "Not Found")
            return
        self.send_response(200)
        self.send_common_headers()
        self.send_header("Content-Type", MIME.get(ext, "application/octet-stream"))
        if ext in COMPRESSIBLE:
            self.send_header("Vary", "Accept-Encoding")
        if encoding:
            self.send_header("Content-Encoding", encoding)
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def encoded(self, target, ext):
        """(content coding or None, body) for `target` as this client takes it."""
        if ext not in COMPRESSIBLE:
            with open(target, "rb") as f:
                return None, f.read()
        accepted = accepted_encodings(self.headers.get("Accept-Encoding"))
        stat = os.stat(target)
        for encoding, suffix in PRECOMPRESSED:
            sibling = target + suffix
            if encoding not in accepted or not os.path.isfile(sibling):
                continue
            # The sibling must be inside the root too (it could be a symlink) and up to date.
            real = os.path.realpath(sibling)
            if not real.startswith(self.root + os.sep) or os.stat(real).st_mtime < stat.st_mtime:
                continue
            with open(real, "rb") as f:
                return encoding, f.read()
        with open(target, "rb") as f:
            body = f.read()
        if "gzip" not in accepted or len(body) < 1024:
            return None, body
        key = (stat.st_size, stat.st_mtime_ns)
        cached = Handler.gzipped.get(target)
        if cached is None or cached[0] != key:
            cached = (key, gzip.compress(body, compresslevel=6, mtime=0))
            Handler.gzipped[target] = cached
        return "gzip", cached[1]

    def do_POST(self):
        self.fail(405, "Method Not Allowed")

    do_PUT = do_DELETE = do_PATCH = do_POST


class Server(http.server.ThreadingHTTPServer):
    # The page's first load opens many connections at once (a wasm module per worker thread);
    # socketserver's backlog of 5 made some wait for SYN retries (27 s worst case at 200).
    request_queue_size = 256
    daemon_threads = True


def main():
    parser = argparse.ArgumentParser(description="procfit development server")
    parser.add_argument("--root", default=os.path.join(os.path.dirname(__file__), ".."))
    parser.add_argument("--port", type=int, default=int(os.environ.get("PORT", "8080")))
    parser.add_argument("--no-isolation", action="store_true", help="omit COOP/COEP headers")
    args = parser.parse_args()

    Handler.root = os.path.realpath(args.root)
    Handler.isolation = not args.no_isolation
    try:
        server = Server(("127.0.0.1", args.port), Handler)
    except OSError as e:
        if e.errno == errno.EADDRINUSE:
            print(
                f"serve: port {args.port} is busy; pick another, e.g. PORT={args.port + 1} make serve",
                file=sys.stderr,
            )
            sys.exit(1)
        raise
    port = server.server_address[1]
    print(f"http://127.0.0.1:{port}/", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
