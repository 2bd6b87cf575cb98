"""The one exception type the client raises."""

import grpc


class LuxelError(Exception):
    """A failed call: ``code`` is the gRPC status code name ("NOT_FOUND",
    "DATA_LOSS", "INVALID_ARGUMENT", ...) and ``message`` the daemon's text,
    which names the offending field or id.

    Problems found on the client side before anything is sent (a missing
    resource file, an unknown setting) use the same codes, with ``local`` set.
    """

    def __init__(self, code, message, local=False):
        super().__init__(f"{code}: {message}")
        self.code = code
        self.message = message
        self.local = local

    @classmethod
    def from_rpc_error(cls, error):
        """Translates a grpc.RpcError (a failed call) into a LuxelError."""
        code = error.code() if hasattr(error, "code") else grpc.StatusCode.UNKNOWN
        details = error.details() if hasattr(error, "details") else str(error)
        name = code.name if isinstance(code, grpc.StatusCode) else str(code)
        return cls(name, details or "")
