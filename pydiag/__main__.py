import sys

from pydiag.cli import main

sys.exit(main())
