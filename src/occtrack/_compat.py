"""What differs between the Python versions occtrack supports (3.10 to 3.13)."""

import sys

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10 (ROS 2 Humble's): the same parser, as a package
    import tomli as tomllib

__all__ = ["tomllib"]
