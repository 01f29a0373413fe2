import sys

from zoetic.cli import main

sys.exit(main())
