#!/usr/bin/env python3
"""OctoPrint's virtual printer (a printer simulation nobody here wrote) behind a pseudo-terminal.

Runs the `VirtualPrinter` class of OctoPrint's bundled `virtual_printer` plugin (installed from
PyPI, see scripts/test.sh) with its default settings - the simulated errors at lines 100
(resend), 105 (resend, then the next line is dropped), 110 (missing line number) and 115
(checksum mismatch) - plus an optional resend ratio, and connects it to the master side of a
pseudo-terminal whose slave path is printed on stdout. `clayloft print` opens that path like any
serial port.

The printer's own view of the job is written to --events as it happens, one event per line:
  accept N     the printer took numbered line N (its last line number moved from N-1 to N)
  exec N CMD   the printer executed CMD while its last line number was N
  resend R     the printer asked for line R again
The bridge exits when the host closes the port after having talked to it.

Usage: octoprint_virtual.py --events FILE [--resend-ratio PERCENT] [--speedup K]
"""

import argparse
import errno
import os
import sys
import tempfile
import threading
import time
import tty

from octoprint.plugins.virtual_printer import VirtualPrinterPlugin
from octoprint.plugins.virtual_printer import virtual


class Settings:
    """The plugin's own defaults, with a few overrides; the part of OctoPrint's settings API the
    virtual printer reads."""

    def __init__(self, overrides, basefolder):
        self._values = VirtualPrinterPlugin().get_settings_defaults()
        self._values.update(overrides)
        self._basefolder = basefolder

    def get(self, path, merged=False, **_):
        value = self._values
        for key in path:
            value = value.get(key) if isinstance(value, dict) else None
        return value

    def get_int(self, path, **_):
        v = self.get(path)
        return None if v is None else int(v)

    def get_float(self, path, **_):
        v = self.get(path)
        return None if v is None else float(v)

    def get_boolean(self, path, **_):
        return bool(self.get(path))

    def global_get_basefolder(self, name, **_):
        folder = os.path.join(self._basefolder, name)
        os.makedirs(folder, exist_ok=True)
        return folder


class NoPlugins:
    """OctoPrint's plugin manager as the virtual printer sees it: no plugins with custom actions."""

    def get_hooks(self, _name):
        return {}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--events", required=True)
    ap.add_argument("--resend-ratio", type=int, default=0)
    ap.add_argument("--speedup", type=float, default=100.0)
    args = ap.parse_args()

    events = open(args.events, "w", buffering=1)
    lock = threading.Lock()

    def log(line):
        with lock:
            events.write(line + "\n")

    class LoggingPrinter(virtual.VirtualPrinter):
        """The virtual printer, unchanged, with its line-number bookkeeping and command execution
        observed."""

        @property
        def lastN(self):
            return self.__dict__.get("_observed_lastN", 0)

        @lastN.setter
        def lastN(self, value):
            old = self.__dict__.get("_observed_lastN", 0)
            self.__dict__["_observed_lastN"] = value
            if value == old + 1:
                log(f"accept {value}")

        def _triggerResend(self, expected=None, actual=None, checksum=None):
            requested = expected if expected is not None else self.lastN + 1
            log(f"resend {requested}")
            return super()._triggerResend(expected=expected, actual=actual, checksum=checksum)

    class ObservedRegex:
        """Wraps the printer's command pattern: it is matched once per command executed."""

        def __init__(self, inner, printer_ref):
            self.inner = inner
            self.printer_ref = printer_ref

        def match(self, data):
            printer = self.printer_ref[0]
            if printer is not None and data.strip():
                log(f"exec {printer.lastN} {data.strip()}")
            return self.inner.match(data)

    # The virtual printer asks the server's plugin manager for custom-action hooks; there is no
    # server here.
    virtual.plugin_manager = lambda: NoPlugins()

    printer_ref = [None]
    # Matched as `VirtualPrinter.command_regex` inside the printer, so the class attribute itself.
    virtual.VirtualPrinter.command_regex = ObservedRegex(
        virtual.VirtualPrinter.command_regex, printer_ref
    )

    base = tempfile.mkdtemp(prefix="clayloft-virtual-printer-")
    settings = Settings(
        {
            "resend_ratio": args.resend_ratio,
            # Idle `wait` lines every second are kept (they are what the printer really says).
            "throttle": 0.0,
        },
        base,
    )
    printer = LoggingPrinter(settings, None, data_folder=base, read_timeout=0.05)
    printer_ref[0] = printer
    # Moves are simulated at their feed rate (already 10x fast); faster still for a test.
    printer._feedrate_multiplier = 100.0 * args.speedup
    printer._flowrate_multiplier = 100.0 * args.speedup

    master, slave = os.openpty()
    tty.setraw(slave)
    print(os.ttyname(slave), flush=True)
    os.close(slave)

    connected = threading.Event()
    done = threading.Event()

    def to_host():
        connected.wait()
        while not done.is_set():
            line = printer.readline()
            if not line:
                continue
            if not line.endswith(b"\n"):
                line += b"\n"  # its lines are handed to OctoPrint one by one, without line ends
            try:
                os.write(master, line)
            except OSError:
                done.set()

    writer = threading.Thread(target=to_host, daemon=True)
    writer.start()

    while not done.is_set():
        try:
            data = os.read(master, 4096)
        except OSError as e:
            if e.errno == errno.EIO:
                if connected.is_set():
                    break  # the host closed the port
                time.sleep(0.005)  # not opened yet
                continue
            raise
        if not data:
            continue
        connected.set()
        printer.write(data)

    done.set()
    # Its worker threads trip over the closed queues on their way out; that is not our news.
    threading.excepthook = lambda _args: None
    printer.close()
    events.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
