#include "channel_target.hpp"

#include <arpa/inet.h>

#include <stdexcept>
#include <vector>

namespace shadow::client {
namespace {

std::vector<std::string> split(const std::string& addresses) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    const size_t comma = addresses.find(',', start);
    parts.push_back(addresses.substr(start, comma - start));
    if (parts.back().empty())
      throw std::invalid_argument("server '" + addresses + "': an empty address");
    if (comma == std::string::npos) return parts;
    start = comma + 1;
  }
}

// "HOST:PORT" or "[V6]:PORT" -> HOST / V6; throws without a numeric port.
std::string host_of(const std::string& address) {
  const size_t colon = address.rfind(':');
  const std::string port = colon == std::string::npos ? "" : address.substr(colon + 1);
  if (port.empty() || port.find_first_not_of("0123456789") != std::string::npos)
    throw std::invalid_argument("server '" + address + "': expected HOST:PORT");
  std::string host = address.substr(0, colon);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  return host;
}

// 4 or 6 for an IP literal, 0 for anything else.
int ip_family(const std::string& host) {
  unsigned char buffer[16];
  if (inet_pton(AF_INET, host.c_str(), buffer) == 1) return 4;
  if (inet_pton(AF_INET6, host.c_str(), buffer) == 1) return 6;
  return 0;
}

}  // namespace

std::string channel_target(const std::string& addresses) {
  const std::vector<std::string> parts = split(addresses);
  if (parts.size() == 1) return parts[0];
  int family = 0;
  for (const std::string& part : parts) {
    const int f = ip_family(host_of(part));
    if (f == 0)
      throw std::invalid_argument("server '" + part +
                                  "': several servers must be IP:PORT literals; for host names "
                                  "use one DNS name (dns:///NAME:PORT) that resolves to each");
    if (family != 0 && f != family)
      throw std::invalid_argument("server '" + addresses + "': mixes IPv4 and IPv6");
    family = f;
  }
  return (family == 4 ? "ipv4:" : "ipv6:") + addresses;
}

std::string first_host(const std::string& addresses) {
  return host_of(split(addresses)[0]);
}

}  // namespace shadow::client
