// The ROS1 bag library's package lookup, without rospack.
//
// Every rosbag::Bag builds a pluginlib::ClassLoader for its encryptor
// plugins. Debian's pluginlib asks the ament index for the package
// rosbag_storage first and, not finding it there, falls back to
// ros::package::getPath and ros::package::getPlugins (libroslib), which run a
// rospack crawl: it prints "[rospack] Warning ..." lines on stderr when the
// home folder is not writable and otherwise writes ~/.ros/rospack_cache_*,
// a file outside --out, on every run.
//
// These two definitions take the place of libroslib's for this program (the
// dynamic linker binds librosbag_storage's calls to the first definition in
// load order; rvlio_io comes before libroslib, a dependency of
// librosbag_storage). They look a package up the way rospack finds one in
// its search path, without crawling or a cache: ROS_PACKAGE_PATH's folders,
// then /usr/share (where Debian installs the ROS packages), each
// <root>/<package>/package.xml. getPlugins reports the package's own export
// `<package attribute="...">` (${prefix} = the package folder), which is the
// only one a bag reader needs (rosbag_storage/encryptor_plugins.xml);
// rospack would also add the exports of the packages that depend on it.
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <sys/stat.h>

#include <ros/package.h>

namespace rvlio::bag_detail {
namespace {

bool IsFile(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

std::vector<std::string> PackageRoots() {
  std::vector<std::string> roots;
  if (const char* env = std::getenv("ROS_PACKAGE_PATH")) {
    const std::string list = env;
    size_t start = 0;
    while (start <= list.size()) {
      const size_t end = std::min(list.find(':', start), list.size());
      if (end > start) roots.push_back(list.substr(start, end - start));
      start = end + 1;
    }
  }
  roots.push_back("/usr/share");
  return roots;
}

// The package's folder, or "" when no root holds it.
std::string FindPackage(const std::string& name) {
  if (name.empty()) return "";
  for (const char c : name)  // ROS package names: letters, digits, underscores
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return "";
  for (const std::string& root : PackageRoots())
    if (IsFile(root + "/" + name + "/package.xml")) return root + "/" + name;
  return "";
}

bool IsSpace(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }
bool IsWordChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; }

// The value of `attribute="..."` inside one tag's text (between the tag name
// and its '>'), or false when the tag has no such attribute.
bool AttributeValue(const std::string& tag, const std::string& attribute, std::string* value) {
  for (size_t at = tag.find(attribute); at != std::string::npos;
       at = tag.find(attribute, at + 1)) {
    if (at > 0 && IsWordChar(tag[at - 1])) continue;  // a longer name ending in it
    size_t i = at + attribute.size();
    while (i < tag.size() && IsSpace(tag[i])) ++i;
    if (i >= tag.size() || tag[i] != '=') continue;
    for (++i; i < tag.size() && IsSpace(tag[i]);) ++i;
    if (i >= tag.size() || tag[i] != '"') continue;
    const size_t end = tag.find('"', i + 1);
    if (end == std::string::npos) return false;
    *value = tag.substr(i + 1, end - i - 1);
    return true;
  }
  return false;
}

// The `attribute` values of every <package ...> tag of the XML text (the
// export tags of package.xml are named after the exporting package).
std::vector<std::string> ExportValues(const std::string& xml, const std::string& package,
                                      const std::string& attribute) {
  std::vector<std::string> values;
  const std::string open = "<" + package;
  for (size_t at = xml.find(open); at != std::string::npos; at = xml.find(open, at + 1)) {
    const size_t name_end = at + open.size();
    if (name_end >= xml.size() || !IsSpace(xml[name_end])) continue;
    const size_t close = xml.find('>', name_end);
    if (close == std::string::npos) break;
    std::string value;
    if (AttributeValue(xml.substr(name_end, close - name_end), attribute, &value))
      values.push_back(value);
  }
  return values;
}

}  // namespace
}  // namespace rvlio::bag_detail

namespace ros::package {

__attribute__((visibility("default"))) std::string getPath(const std::string& package_name) {
  return rvlio::bag_detail::FindPackage(package_name);
}

__attribute__((visibility("default"))) void getPlugins(const std::string& package,
                                                       const std::string& attribute,
                                                       std::vector<std::string>& plugins,
                                                       bool /*force_recrawl*/) {
  const std::string dir = rvlio::bag_detail::FindPackage(package);
  if (dir.empty()) return;
  std::ifstream in(dir + "/package.xml");
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (std::string value : rvlio::bag_detail::ExportValues(xml, package, attribute)) {
    const std::string prefix = "${prefix}";
    for (size_t p = value.find(prefix); p != std::string::npos; p = value.find(prefix))
      value.replace(p, prefix.size(), dir);
    plugins.push_back(value);
  }
}

}  // namespace ros::package
