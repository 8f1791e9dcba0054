// Which gRPC target a client dials: one server, several replicas, or a DNS name.
#pragma once

#include <string>

namespace shadow::client {

// One address is gRPC's own target syntax, passed through ("HOST:PORT", "dns:///NAME:PORT",
// "ipv4:A:P,B:P", ...). Several, separated by commas, must be IP:PORT literals of one family
// ("127.0.0.1:5001,127.0.0.2:5001" -> "ipv4:127.0.0.1:5001,127.0.0.2:5001"), since gRPC resolves
// no list of host names; for those use one DNS name that resolves to every replica. Throws
// std::invalid_argument naming the address for anything else.
std::string channel_target(const std::string& addresses);

// The host of the first address ("127.0.0.1" for "127.0.0.1:5001,..."): the name a TLS server
// certificate is checked against when several replicas are dialled.
std::string first_host(const std::string& addresses);

}  // namespace shadow::client
