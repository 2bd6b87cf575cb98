// Percent-decoding of the relative file URIs a glTF file names its buffers
// and images with (RFC 3986 references: "tex%20a.png" is the file
// "tex a.png"). The importer, the daemon's upload checks and the CLI's upload
// all decode through this one function, so they agree on which file a URI
// names and on which URIs are refused.
#pragma once

#include <string>
#include <string_view>

#include "common/status.h"

namespace luxel {

// Decodes every "%XX" (two hex digits, either case) to its byte. Everything
// else is copied as is: '+' stays '+' (form encoding is not a URI rule) and
// UTF-8, raw or escaped ("%C3%A9"), passes through byte for byte.
//
// INVALID_ARGUMENT naming the URI and the offending escape for a '%' not
// followed by two hex digits ("%", "%4", "%zz") and for "%00": a NUL byte
// cannot be part of a file name, and a decoder that kept it would let
// "a.png%00.txt" mean different files to different readers. Callers prefix
// the message with where the URI came from ("images[3].uri").
Result<std::string> percent_decode_uri(std::string_view uri);

}  // namespace luxel
