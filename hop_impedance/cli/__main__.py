"""``python -m hop_impedance.cli``."""

import sys

from hop_impedance.cli.main import main

sys.exit(main())
