import sys

from sketchforge.cli import main

# Guarded: a spawned child process (sketchforge.offload) imports this module again.
if __name__ == "__main__":
    sys.exit(main())
