"""massprops: exact mass properties of closed meshes and Newton-Euler dynamics of one rigid body.

The library never prints and never exits; the command line lives in ``massprops.cli``.
"""

from __future__ import annotations

__version__ = "0.1.0"
