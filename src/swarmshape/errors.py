"""The exception types that end a command with a word rather than a traceback: bad user input
(one line on stderr, exit 2), a plug-in's own failure (the same), and a stop from outside."""


class InputError(ValueError):
    """Input that cannot be used; the message names the culprit and says what to do."""


class _AboutASetting(Exception):
    """A problem with one setting, named as files and Python spell it (``max_speed``); the
    command line shows its flag instead (``--max-speed``)."""

    def __init__(self, setting: str, problem: str) -> None:
        super().__init__(setting, problem)
        self.setting = setting
        self.problem = problem

    def __str__(self) -> str:
        return f"{self.setting} {self.problem}"


class SettingError(_AboutASetting, InputError):
    """A setting with a value that cannot be used."""


class SettingWarning(_AboutASetting, UserWarning):
    """A setting was given that changes nothing in this run (the plug-in never reads it)."""


class PluginError(InputError):
    """A plug-in's code failed (raised, wrote where it may only read, named a robot that does
    not exist, called sys.exit); the message names the plug-in and its line."""


class Stopped(BaseException):
    """The run was stopped from outside its code (a time limit): never a plug-in's failure,
    wherever it struck."""


class Terminated(SystemExit):
    """The process was asked to end by a signal (SIGTERM, SIGHUP): a run unwinds as after
    Ctrl+C, so that it leaves no temporary file, and exits with 128 + the signal's number."""
