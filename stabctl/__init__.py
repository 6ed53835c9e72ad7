"""stabctl: transient-stability control of power systems with distributed energy storage.

Per unit on the system base unless a name says otherwise; time in s; angles in rad;
frequencies in Hz.
"""

__version__ = "0.1.0"
