"""The one error type of the Modelica -> FMU bridge."""


class ModelicaBuildError(Exception):
    """A model that cannot be built: the message names the construct and, where known, file:line."""

    def __init__(self, message: str, location: str | None = None) -> None:
        self.location = location
        super().__init__(f"{location}: {message}" if location else message)
