#pragma once
// A receiver never trusts a message. CheckMessage() returns "" when a decoded message is
// sane (counts match array sizes, enums known, values finite where they must be), or a
// one-line reason to drop it.

#include <string>

#include "sarmap/message_registry.h"

namespace sarmap {
namespace common {

#define SARMAP_DECLARE_CHECK(T) std::string CheckMessage(const sarmap::T& msg);
SARMAP_FOR_EACH_MESSAGE_TYPE(SARMAP_DECLARE_CHECK)
#undef SARMAP_DECLARE_CHECK

}  // namespace common
}  // namespace sarmap
