"""`python -m rostool.graph.daemon --backend B`: the daemon process (client.py starts it detached)."""

import sys

from rostool.graph.daemon.server import main

sys.exit(main())
