"""Telling the user that stabctl is compiling: a notice when the first kernel of the
process starts compiling (loading cached kernels does not count) and a heartbeat while
compiling lasts (numba's event API, ``numba:compile``)."""

from __future__ import annotations

import threading
import time

from numba.core import event

#: what each long-compiling kernel is (its function's name) and the seconds its compile
#: took with an empty cache on the 2-core development machine, under the load of other
#: work (`stabctl compile kundur`, 2026-12-03: 126 s and 109 s for the model's
#: evaluation in two runs; the stepping loop 99 s and 84 s, in its child process)
REFERENCE_S = {
    "evaluate_kernel": ("the model's evaluation", 120.0),
    "integrate": ("the stepping loop", 95.0),
    "_differences": ("the linearisation", 5.0),
    "_swing_batch": ("the estimators' filters", 4.5),
    "_freq_batch": ("the estimators' filters", 1.5),
}


def still_line(seconds: float, kernel: str, kernel_s: float) -> str:
    """The line a long compile repeats (`on_first_compile`'s ``still``): the seconds
    since the first compile began, the kernel compiling now and, for one of
    `REFERENCE_S`, how long it took on the reference machine and the time left by it
    (past it: that it is past).

    Parameters
    ----------
    seconds : float
        Since the first compile of the process began, s.
    kernel : str
        The compiling function's name.
    kernel_s : float
        Since this kernel began compiling, s.

    Returns
    -------
    str
        One line.
    """
    head = f"stabctl: still compiling ({seconds:.0f} s)"
    if kernel not in REFERENCE_S:
        return f"{head}: {kernel}, {kernel_s:.0f} s"
    what, ref = REFERENCE_S[kernel]
    if kernel_s < ref:
        return (
            f"{head}: {what}, {kernel_s:.0f} s of about {ref:.0f} s on the 2-core reference "
            f"machine ({kernel_s / ref:.0%}), about {ref - kernel_s:.0f} s left"
        )
    return (
        f"{head}: {what}, {kernel_s:.0f} s, past the {ref:.0f} s it takes on the 2-core "
        "reference machine (a loaded or slower machine takes longer)"
    )


def on_first_compile(notify, still=None, every_s: float = 10.0):
    """Call ``notify()`` once, when numba starts compiling the first stabctl kernel of
    this process (numba's event API, ``numba:compile``); loading cached kernels does not
    count.  Then, whenever compiling has gone on for `every_s` seconds, call
    ``still(seconds since the first compile began, the name of the function compiling,
    seconds since it began)`` (`still_line` words it), and again every `every_s` seconds
    while compiling goes on (also across compiles that follow one another), so that a long
    compile is never a silent wait; the seconds only grow (one compile after another is
    one wait to the user).

    Parameters
    ----------
    notify : callable
        Called with no arguments.
    still : callable, optional
        Called with the seconds (float) since the first compile began, the compiling
        function's name (str) and the seconds since it began, from a background thread.
    every_s : float
        Interval of the `still` calls (s).

    Returns
    -------
    callable
        Stops listening (no call after it).
    """

    class _Compiles(event.Listener):
        depth, noticed, t_first, last = 0, False, 0.0, 0.0
        kernel, t_kernel = "", 0.0

        def on_start(self, ev):
            if self.depth == 0:  # a compile begins (numba's overloads nest)
                now = time.perf_counter()
                self.kernel = ev.data["dispatcher"].py_func.__name__
                self.t_kernel = now
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
                    still(now - self.t_first, self.kernel, now - max(self.t_kernel, self.t_first))

    listener, halt = _Compiles(), threading.Event()

    def stop():
        if not halt.is_set():
            halt.set()
            event.unregister("numba:compile", listener)

    event.register("numba:compile", listener)
    return stop
