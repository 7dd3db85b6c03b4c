import sys

from p105cli.cli import main

sys.exit(main())
