"""What every command line shares: adding a command, reading its dataset, and settings as config keys with
flag aliases, ``--set`` and ``--print-config``."""
