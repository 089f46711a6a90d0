"""``python -m yarf.farm``: the yarf-farm command line."""

from yarf.farm.cli import main

raise SystemExit(main())
