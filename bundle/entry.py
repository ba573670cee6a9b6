"""The bundle's executable: the same command line as the installed package's ``groundstation``."""

import multiprocessing

from groundstation.cli import main

if __name__ == "__main__":
    multiprocessing.freeze_support()  # evaluate DIR's workers and the first start's kernel compiler start from this executable too
    raise SystemExit(main())
