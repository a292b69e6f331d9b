"""``python -m massprops``: the same as the ``massprops`` command."""

from massprops.cli import main

main()
