#pragma once
// dynamic_reconfigure knobs that stay runtime changes (docs/ros_nodes_notes.md, "Startup policy").
//
// dynamic_reconfigure::Server writes every knob to the node's parameters, at start (the .cfg
// default where none was set) and after every change. A node restarted without its launch file
// setting the parameters again (respawn, `nodelet load` by hand, a restarted manager) would then
// start with the knobs of the earlier run instead of the launch file's (yaml's) values, and
// nothing would say so. RuntimeKnobs gives the server a node handle whose knob names are remapped
// to /runtime_knobs/<node namespace>/<knob>: the server starts from the node's parameters (copied
// there first) and writes its values there, never to the node's parameters. A knob changed at run
// time lives until the node stops; a restart starts from what the launch file, a yaml or
// `rosparam set` left in the node's namespace. While the node runs, its current knob values can be
// read under /runtime_knobs/...; they are deleted when it stops.

#include <dynamic_reconfigure/server.h>
#include <ros/node_handle.h>
#include <ros/param.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <boost/thread/recursive_mutex.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ebslam_ros_common {

template <typename Config>
class RuntimeKnobs {
 public:
  using Callback = std::function<void(Config&, std::uint32_t)>;

  /// The server in `nh`'s namespace (services, topics and callback queue as
  /// dynamic_reconfigure::Server(mutex, nh)); its initial values are the parameters set below `nh`
  /// (the .cfg defaults for the others).
  RuntimeKnobs(boost::recursive_mutex& mutex, const ros::NodeHandle& nh) {
    std::map<std::string, std::string> remappings;
    for (const auto& description : Config::__getParamDescriptions__()) {
      const std::string real = nh.resolveName(description->name);
      const std::string shadow = "/runtime_knobs" + real;
      remappings[real] = shadow;
      shadows_.push_back(shadow);
      XmlRpc::XmlRpcValue value;
      if (ros::param::get(real, value)) {
        ros::param::set(shadow, value);
      } else {
        ros::param::del(shadow);
      }
    }
    ros::NodeHandle knobs_nh(nh.getNamespace(), remappings);
    knobs_nh.setCallbackQueue(nh.getCallbackQueue());
    server_ = std::make_unique<dynamic_reconfigure::Server<Config>>(mutex, knobs_nh);
  }
  explicit RuntimeKnobs(const ros::NodeHandle& nh) : RuntimeKnobs(own_mutex_, nh) {}
  ~RuntimeKnobs() {
    server_.reset();
    for (const std::string& shadow : shadows_) ros::param::del(shadow);
  }
  RuntimeKnobs(const RuntimeKnobs&) = delete;
  RuntimeKnobs& operator=(const RuntimeKnobs&) = delete;

  /// As dynamic_reconfigure::Server::updateConfig (the knobs' values shown to clients).
  void updateConfig(const Config& config) { server_->updateConfig(config); }
  /// As dynamic_reconfigure::Server::setCallback: `callback` runs now with the current values and
  /// then with every change a client requests.
  void setCallback(const Callback& callback) { server_->setCallback(callback); }

 private:
  boost::recursive_mutex own_mutex_;
  std::vector<std::string> shadows_;  // the knobs' full names under /runtime_knobs
  std::unique_ptr<dynamic_reconfigure::Server<Config>> server_;
};

}  // namespace ebslam_ros_common
