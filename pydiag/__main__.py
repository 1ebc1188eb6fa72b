import sys

from pydiag.app.cli import main

sys.exit(main())
