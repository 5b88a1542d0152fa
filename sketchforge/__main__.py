import sys

from sketchforge.cli import main

sys.exit(main())
