"""A CPU's edges wired together in one process: its end of the bus, the recording and,
beside it, the browser view."""
