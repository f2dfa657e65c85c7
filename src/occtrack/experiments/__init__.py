"""Reproductions of the paper's tables, one module each, run by `occtrack reproduce NAME`.

Each module defines NAME, HELP, `configure(parser)` and `run(args) -> int`, like a CLI command.
"""
