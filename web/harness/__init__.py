"""A chart in a CPU: loading and compiling it, the session that runs it, the plant, the
state file and the project directory."""
