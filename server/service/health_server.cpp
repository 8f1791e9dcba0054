#include "service/health_server.hpp"

#include <stdexcept>
#include <vector>

#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_builder.h>

#include "service/server.hpp"
#include "service/start_up.hpp"

namespace shadow::service {

std::unique_ptr<grpc::Server> start_health_server(const std::string& listen, std::string* address) {
  grpc::ServerBuilder builder;
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);  // a taken port fails the start
  int port = 0;
  builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), &port);
  // Its only services: the default health service and reflection, both enabled for the process
  // by ShadowServer.
  std::unique_ptr<grpc::Server> server;
  std::vector<std::string> bind_log;
  {
    GrpcLogCapture capture;  // a taken port: one line of the server's, not gRPC's raw one
    server = builder.BuildAndStart();
    if (server && port != 0)
      capture.print();
    else
      bind_log = capture.lines();
  }
  if (!server || port == 0)
    throw std::runtime_error("--health-listen: " + cannot_listen(listen, bind_log));
  *address = listen.substr(0, listen.rfind(':')) + ":" + std::to_string(port);
  grpc::HealthCheckServiceInterface* health = server->GetHealthCheckService();
  health->SetServingStatus(kServiceName, true);
  health->SetServingStatus("", true);
  return server;
}

}  // namespace shadow::service
