"""The exception types for bad user input: the CLI turns them into a one-line message, exit 2."""


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
