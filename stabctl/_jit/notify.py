"""Telling the user that stabctl is compiling: a notice when the first kernel of the
process starts compiling (loading cached kernels does not count) and a heartbeat while
compiling lasts (numba's event API, ``numba:compile``)."""

from __future__ import annotations

import threading
import time

from numba.core import event


def on_first_compile(notify, still=None, every_s: float = 10.0):
    """Call ``notify()`` once, when numba starts compiling the first stabctl kernel of
    this process (numba's event API, ``numba:compile``); loading cached kernels does not
    count.  Then, whenever compiling has gone on for `every_s` seconds, call
    ``still(seconds since the first compile began)``, and again every `every_s` seconds
    while compiling goes on (also across compiles that follow one another), so that a long
    compile is never a silent wait; the seconds only grow (one compile after another is
    one wait to the user).

    Parameters
    ----------
    notify : callable
        Called with no arguments.
    still : callable, optional
        Called with the seconds (float) since the first compile began, from a background
        thread.
    every_s : float
        Interval of the `still` calls (s).

    Returns
    -------
    callable
        Stops listening (no call after it).
    """

    class _Compiles(event.Listener):
        depth, noticed, t_first, last = 0, False, 0.0, 0.0

        def on_start(self, ev):
            if self.depth == 0:  # a compile begins (numba's overloads nest)
                now = time.perf_counter()
                if now - self.last > every_s:  # else it follows the last one: keep the
                    self.last = now  # beat, never more than every_s apart
            self.depth += 1
            if not self.noticed and ev.data["dispatcher"].py_func.__module__.startswith("stabctl."):
                self.noticed = True
                self.t_first = time.perf_counter()
                notify()
                if still is not None:
                    threading.Thread(target=self.beat, daemon=True).start()

        def on_end(self, ev):
            self.depth -= 1

        def beat(self):
            while not halt.wait(min(1.0, every_s)):
                now = time.perf_counter()
                if self.depth > 0 and now - self.last >= every_s:
                    self.last = now
                    still(now - self.t_first)

    listener, halt = _Compiles(), threading.Event()

    def stop():
        if not halt.is_set():
            halt.set()
            event.unregister("numba:compile", listener)

    event.register("numba:compile", listener)
    return stop
