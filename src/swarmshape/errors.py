"""The one exception type for bad user input: the CLI turns it into a one-line message, exit 2."""


class InputError(ValueError):
    """Input that cannot be used; the message names the culprit and says what to do."""
