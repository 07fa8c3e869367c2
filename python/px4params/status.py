"""Exit statuses of commands, ours and the NSH `param` verbs alike, as shells and NSH scripts read
them (`if param compare ...`)."""

#: Success; for ``param compare``/``greater``: the value matched.
EXIT_OK = 0
#: The command failed (one line on stderr says why); ``compare``: no match; arming refused.
EXIT_FAILED = 1
#: The command line itself is wrong (argparse's usage error).
EXIT_USAGE = 2
#: Interrupted by Ctrl-C (128 + SIGINT), as shells report it.
EXIT_INTERRUPTED = 130
#: The reader of the output went away (``| head -1``): 128 + SIGPIPE, as shells report a
#: program that SIGPIPE ended; nothing is printed.
EXIT_BROKEN_PIPE = 141
