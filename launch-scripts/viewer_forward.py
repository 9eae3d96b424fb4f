#!/usr/bin/env python3
"""Forwards the live page out of the demo's private network namespace (launch-scripts/demo.sh).

The demo runs in a network namespace of its own, so sarmap-viewer's 127.0.0.1 there is not the
host's. A Unix socket is a file, seen from both sides: one half of this forwarder listens on the
host's 127.0.0.1 and passes each connection to the socket, the other half, inside the namespace,
passes it on to the viewer.

  viewer_forward.py host --port 8080 --socket PATH --port-file FILE --parent PID
      listens on 127.0.0.1:8080 (a free port if 8080 is taken), writes the port to FILE
  viewer_forward.py inside --socket PATH [--to-host 10.77.0.3] --to-port 8080 --parent PID
      listens on the socket, connects each client to 127.0.0.1:8080 (or the given address: the
      two-computer demo's viewer runs on the "compute" computer)

Both exit when the process PID is gone (the demo), so nothing is left behind.
"""
import argparse
import asyncio
import os
import socket
import sys


async def pipe(reader, writer):
    try:
        while True:
            data = await reader.read(65536)
            if not data:
                break
            writer.write(data)
            await writer.drain()
    except (ConnectionError, asyncio.CancelledError):
        pass
    finally:
        try:
            writer.close()
        except Exception:
            pass


def handler(connect):
    async def handle(client_reader, client_writer):
        try:
            upstream_reader, upstream_writer = await connect()
        except OSError:
            client_writer.close()
            return
        await asyncio.gather(pipe(client_reader, upstream_writer), pipe(upstream_reader, client_writer))
    return handle


async def watch_parent(pid):
    while True:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return
        except PermissionError:
            pass
        await asyncio.sleep(1)


def host_socket(port):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        s.bind(("127.0.0.1", port))
    except OSError:
        s.bind(("127.0.0.1", 0))  # the preferred port is taken: any free one
    return s


async def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("side", choices=["host", "inside"])
    parser.add_argument("--socket", required=True)
    parser.add_argument("--port", type=int, default=8080)
    parser.add_argument("--port-file")
    parser.add_argument("--to-host", default="127.0.0.1")
    parser.add_argument("--to-port", type=int, default=8080)
    parser.add_argument("--parent", type=int, required=True)
    args = parser.parse_args()
    if args.side == "host":
        sock = host_socket(args.port)
        server = await asyncio.start_server(
            handler(lambda: asyncio.open_unix_connection(args.socket)), sock=sock)
        if args.port_file:
            with open(args.port_file + ".tmp", "w") as f:
                f.write("%d\n" % sock.getsockname()[1])
            os.rename(args.port_file + ".tmp", args.port_file)
    else:
        if os.path.exists(args.socket):
            os.unlink(args.socket)
        server = await asyncio.start_unix_server(
            handler(lambda: asyncio.open_connection(args.to_host, args.to_port)), path=args.socket)
    async with server:
        await watch_parent(args.parent)
    if args.side == "inside" and os.path.exists(args.socket):
        os.unlink(args.socket)


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        sys.exit(0)
