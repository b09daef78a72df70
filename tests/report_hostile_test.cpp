// Run folders with hostile names and contents (a script or another site as a link, bytes that
// are not UTF-8, bidirectional controls) give reports and an index whose every link is a local
// file, that run no script and ask no server, and are valid UTF-8 and XML; typed names with such
// characters are refused.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "physgrad/report/compare_view.hpp"
#include "physgrad/report/html_report.hpp"
#include "report_pages_fixture.hpp"
#include "svg_check.hpp"

namespace {

using physgrad::testing::console_messages;
using physgrad::testing::count;
using physgrad::testing::inline_svgs;
using physgrad::testing::is_file_inside;
using physgrad::testing::kChromium;
using physgrad::testing::link_attributes;
using physgrad::testing::page_text_problem;
using physgrad::testing::percent_decoded;
using physgrad::testing::read_file;
using physgrad::testing::ReportPages;
using physgrad::testing::run_chromium;
using physgrad::testing::SvgChecker;
namespace fs = std::filesystem;

// A TCP server on 127.0.0.1 that records the first line of every request made to it, to serve as
// the proxy of every address a browser asks for: nothing can reach the network without showing.
// The host a request to a proxy names: "GET http://HOST/…" or "CONNECT HOST:443 …".
std::string requested_host(const std::string& request) {
  std::string target = request.substr(request.find(' ') + 1);
  target = target.substr(0, target.find(' '));
  if (const std::size_t scheme = target.find("://"); scheme != std::string::npos) {
    target = target.substr(scheme + 3);
  }
  return target.substr(0, target.find_first_of(":/"));
}

// Chromium asks Google's services (sign-in, component updates, network time) of its own accord,
// whatever it shows and whichever switches it is given.
bool is_browser_service(std::string_view host) {
  return host.ends_with(".google.com") || host.ends_with(".googleapis.com") ||
         host.ends_with(".gvt1.com");
}

class Listener {
 public:
  Listener() {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    if (fd_ < 0 || ::bind(fd_, reinterpret_cast<sockaddr*>(&address), length) != 0 ||
        ::listen(fd_, 64) != 0 ||
        ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
      ADD_FAILURE() << "cannot listen on 127.0.0.1: " << std::strerror(errno);
      return;
    }
    port_ = ntohs(address.sin_port);
    thread_ = std::thread([this] { serve(); });
  }
  ~Listener() { stop(); }
  int port() const { return port_; }
  // Stops listening; the first line of every request received.
  std::vector<std::string> stop() {
    stopping_ = true;
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    return requests_;
  }

 private:
  void serve() {
    while (!stopping_) {
      pollfd waiting{fd_, POLLIN, 0};
      if (::poll(&waiting, 1, 50) <= 0) continue;
      const int connection = ::accept(fd_, nullptr, nullptr);
      if (connection < 0) continue;
      std::string request;
      pollfd reading{connection, POLLIN, 0};
      std::array<char, 512> buffer{};
      if (::poll(&reading, 1, 2000) > 0) {
        const ssize_t n = ::read(connection, buffer.data(), buffer.size());
        if (n > 0) request.assign(buffer.data(), static_cast<std::size_t>(n));
      }
      requests_.push_back(request.substr(0, request.find('\r')));
      ::close(connection);  // no answer: the browser sees a failed request
    }
  }

  int fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
  std::vector<std::string> requests_;
};

class HostileFolders : public ReportPages {
 protected:
  // Run folders in runs/ that attack its index: names that read as a script or another site when
  // linked as they are, or that hold the characters ending a URL's path (# ?), an escape (%) and
  // a byte that is not UTF-8; a learning folder written by hand whose experiment and labels (in
  // summary.json and metrics.csv) hold bidirectional controls, U+FFFF, a control character and
  // a byte that is not UTF-8. Then `physgrad report runs`; false (with a failure) when a step
  // fails.
  bool make_hostile_index() {
    for (const std::string& name :
         {kScriptName, std::string("http:127.0.0.1:9"), std::string("http:attacker.invalid"),
          std::string("a#b?c%41 d"), std::string("plain")}) {
      const physgrad::testing::Outcome outcome =
          run("run comparison --iters 2 --out 'runs/" + name + "'");
      if (outcome.exit_code != 0) {
        ADD_FAILURE() << name << ": " << outcome.err;
        return false;
      }
    }
    fs::rename(dir_ / "runs" / "plain", dir_ / "runs" / kNotUtf8Name);
    const fs::path learning = dir_ / "runs" / "learning";
    fs::create_directories(learning);
    std::ofstream(learning / "summary.json")
        << R"({"experiment": "hig-toy\u202e", "runs": [{"label": "Adam\u202eevil\uffff\u0001",)"
        << R"( "params": {"seed": 0}, "final": {"test_loss": 0.5}}]})";
    const std::string label =
        "Adam\xe2\x80\xae"
        "evil\xef\xbf\xbf\x01\xff\xe2\x81\xa6";
    std::ofstream(learning / "metrics.csv") << "label,seed,wall_seconds,test_loss\n"
                                            << label << ",0,0.5,1\n"
                                            << label << ",0,1,0.5\n"
                                            // Labels that would close the comparison's JSON
                                            // block or open an element, were they not escaped.
                                            << "</script><script>window.pwned=1</script>,1,0.5,1\n"
                                            << "\"\"\"><img/src=x/onerror=window.pwned=1>\","
                                               "2,0.5,1\n";
    const physgrad::testing::Outcome index = run("report runs");
    EXPECT_EQ(index.exit_code, 0) << index.err;
    EXPECT_EQ(index.err, "");
    return index.exit_code == 0;
  }

  // index.html and every report.html of the hostile runs, relative to runs/.
  std::vector<std::string> hostile_pages() const {
    std::vector<std::string> pages = {"index.html"};
    for (const auto& entry : fs::directory_iterator(dir_ / "runs")) {
      if (fs::exists(entry.path() / "report.html")) {
        pages.push_back(entry.path().filename().string() + "/report.html");
      }
    }
    return pages;
  }

  // The link in a console message of Chromium (a resolved address) is a file inside runs/, or
  // a section anchor of the index's contents ("#s-" and lower-case letters, digits, '-').
  void expect_local_file(std::string address, const std::string& page) const {
    const std::size_t anchor = address.find("#s-");
    if (page == "index.html" && anchor != std::string::npos) {
      EXPECT_EQ(address.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-", anchor + 3),
                std::string::npos)
          << page << " links to " << address;
      address.erase(anchor);
    }
    const std::string prefix = "file://" + (dir_ / "runs").string() + "/";
    EXPECT_EQ(address.rfind(prefix, 0), 0u) << page << " links to " << address;
    EXPECT_EQ(address.find_first_of("?#"), std::string::npos) << page << " links to " << address;
    EXPECT_TRUE(is_file_inside(percent_decoded(address.substr(7)), dir_ / "runs"))
        << page << " links to " << address << ", not to a file inside runs/";
  }

  inline static const std::string kScriptName = "javascript:void(window.pwned=1)";
  inline static const std::string kNotUtf8Name = "not-utf8-\xff";
};

TEST_F(HostileFolders, NamesAndLabelsGiveLocalLinksAndValidPages) {
  ASSERT_TRUE(make_hostile_index());
  std::size_t links = 0;
  for (const std::string& page : hostile_pages()) {
    const fs::path file = dir_ / "runs" / page;
    const std::string html = read_file(file);
    EXPECT_EQ(page_text_problem(html), "") << page;
    // No script but the interactive comparison's: its JSON block (no '<' inside) and its code.
    const std::size_t data = html.find("<script type=\"application/json\" id=\"pg-compare-data\">");
    const std::size_t scripts = count(html, "<script");
    EXPECT_TRUE(scripts == 0 || (scripts == 2 && data != std::string::npos)) << page;
    if (data != std::string::npos) {
      const std::size_t from = html.find('>', data) + 1, end = html.find("</script>", from);
      EXPECT_EQ(html.find('<', from), end) << page;
      const std::string close = physgrad::compare_section_close();
      EXPECT_EQ(html.substr(end, close.size()), close) << page;
    }
    for (const std::string& link : link_attributes(html)) {
      ++links;
      if (link.rfind("#s-", 0) == 0) {  // the index's contents: an anchor on the page
        EXPECT_EQ(link.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789-", 1),
                  std::string::npos) << page << ": " << link;
        EXPECT_NE(html.find("id=\"" + link.substr(1) + "\""), std::string::npos) << link;
        continue;
      }
      // A report's link to the index in the folder above, else a file in the page's folder.
      const bool up = link == "../index.html" && page != "index.html";
      EXPECT_EQ(link.compare(up ? 1 : 0, 2, "./"), 0) << page << ": " << link;
      EXPECT_EQ(link.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz"
                                       "0123456789-._~%/"),
                std::string::npos)
          << page << ": " << link;
      EXPECT_TRUE(is_file_inside(file.parent_path() / percent_decoded(link), dir_ / "runs"))
          << page << ": " << link;
    }
    for (const std::string& svg : inline_svgs(html)) {
      for (const std::string& problem : SvgChecker::check(svg))
        ADD_FAILURE() << page << ": " << problem;
    }
  }
  EXPECT_GE(links, 5u);  // a report of each comparison folder
  const std::string index = read_file(dir_ / "runs" / "index.html");
  EXPECT_NE(index.find("href=\"./javascript%3Avoid%28window.pwned%3D1%29/report.html\""),
            std::string::npos);
  EXPECT_NE(index.find("href=\"./not-utf8-%FF/report.html\""), std::string::npos);
  EXPECT_NE(index.find(">not-utf8-\xef\xbf\xbd</a>"), std::string::npos);  // shown as U+FFFD
  // The labels, in the table and in the overlay's legend, with U+FFFD in place of what is hidden.
  EXPECT_NE(index.find("Adam\xef\xbf\xbd"
                       "evil\xef\xbf\xbd\xef\xbf\xbd<"),
            std::string::npos);
  EXPECT_NE(index.find("Adam\xef\xbf\xbd"
                       "evil\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd<"),
            std::string::npos);
  // The comparison folders' x-distance and the learning folder's test loss.
  EXPECT_EQ(inline_svgs(index).size(), 2u);
}

TEST_F(HostileFolders, TypedFolderNamesWithBidirectionalControlsOrNoncharactersAreRefused) {
  for (const auto& [name, problem] : std::vector<std::pair<std::string, std::string>>{
           {"a\xe2\x80\xae"
            "b",
            "contains the bidirectional control U+202E at byte 1"},
           {"a\xe2\x81\xa6"
            "b",
            "contains the bidirectional control U+2066 at byte 1"},
           {"a\xef\xbf\xbf"
            "b",
            "contains the noncharacter U+FFFF at byte 1"},
           {"a\xef\xbf\xbe"
            "b",
            "contains the noncharacter U+FFFE at byte 1"}}) {
    const physgrad::testing::Outcome outcome = run("run comparison --iters 2 --out '" + name + "'");
    EXPECT_EQ(outcome.exit_code, 2) << name;
    EXPECT_NE(outcome.err.find(problem), std::string::npos) << outcome.err;
    EXPECT_TRUE(fs::is_empty(dir_)) << name;
  }
  // In a config file as well; and U+2069 in a list value.
  const physgrad::testing::Outcome config =
      run("run comparison --config " + write_config("c.json", R"({"out": "r\u202db"})"));
  EXPECT_EQ(config.exit_code, 2);
  EXPECT_NE(config.err.find("--out: 'r"), std::string::npos) << config.err;
  EXPECT_NE(config.err.find("contains the bidirectional control U+202D at byte 1"),
            std::string::npos)
      << config.err;
  const physgrad::testing::Outcome list =
      run("run comparison --pg-inverse 'gn\xe2\x81\xa9' --out r");
  EXPECT_EQ(list.exit_code, 2);
  EXPECT_NE(list.err.find("contains the bidirectional control U+2069 at byte 2"), std::string::npos)
      << list.err;
  EXPECT_TRUE(fs::is_empty(dir_));
}

// Chromium loads the index and every report of the hostile runs in frames of one page, a copy
// of each page with a script added. The script logs the address every href and src resolves to
// (the browser's own reading of it) and the page's scripts and event-handler attributes, then
// clicks one link: the n-th, for the frame whose address ends in #n (one frame per link). A link
// to a local file (checked to be one inside runs/) is not followed; any other is — a javascript:
// address would run (the hostile one sets window.pwned), an address of another site would be
// asked for. Every request for anything but a file goes through a proxy that is a listening
// socket of this test (`--proxy-server`, loopback addresses not exempted), so a request that
// would leave the machine is seen; a canary request of the frame page shows that it sees them.
TEST_F(HostileFolders, ChromiumRunsNoScriptAndAsksNoServer) {
  if (!fs::exists(kChromium)) GTEST_SKIP() << "no " << kChromium << " (make test installs it)";
  ASSERT_TRUE(make_hostile_index());
  const std::vector<std::string> pages = hostile_pages();
  std::string frames = "<img src=\"http://canary.physgrad.invalid/canary.png\">\n";
  std::vector<std::string> expected;  // the last message of each frame
  for (std::size_t k = 0; k < pages.size(); ++k) {
    std::string html = read_file(dir_ / "runs" / pages[k]);
    const std::string script =
        "<script>window.addEventListener('load', () => {"
        "const frame = '" +
        std::to_string(k) +
        " ' + location.hash.slice(1);"
        "for (const e of document.querySelectorAll('[href],[src]')) {"
        "const raw = e.getAttribute('href') ?? e.getAttribute('src');"
        "console.log('physgrad-link ' + frame + ' ' + new URL(raw, document.baseURI).href); }"
        "const handlers = [...document.querySelectorAll('*')].filter("
        "e => [...e.attributes].some(a => a.name.toLowerCase().startsWith('on'))).length;"
        "const data = document.querySelectorAll('script[type=\"application/json\"]').length;"
        "const box = document.getElementById('pg-compare');"
        "console.log('physgrad-scripts ' + frame + ' ' + (document.scripts.length - data) + ' ' +"
        "data + ' ' + handlers + ' ' + (box ? box.childElementCount > 0 : 'none'));"
        "const a = document.querySelectorAll('a')[Number(location.hash.slice(1))];"
        "if (a) { a.addEventListener('click', event => {"
        "if (a.protocol === 'file:') event.preventDefault(); }); a.click(); }"
        "setTimeout(() => console.log('physgrad-after ' + frame + ' ' +"
        "(window.pwned === undefined ? 'clean' : 'script-ran')), 1000); });</script>\n";
    html.replace(html.rfind("</body>"), 7, script + "</body>");
    // The page's policy allows its own script by hash; the added one is allowed by its own.
    const std::string added = script.substr(8, script.size() - 8 - 10);
    const std::string allowed = "script-src &#39;sha256-";
    if (html.find(allowed) != std::string::npos) {
      html.replace(html.find(allowed), allowed.size(),
                   allowed + physgrad::sha256_base64(added) + "&#39; &#39;sha256-");
    }
    const fs::path copy = dir_ / "runs" / pages[k];
    const std::string checked = "checked_" + copy.filename().string();
    std::ofstream(copy.parent_path() / checked) << html;
    const std::size_t anchors = count(html, "<a ");
    for (std::size_t n = 0; n < std::max<std::size_t>(anchors, 1); ++n) {
      frames +=
          "<iframe src=\"" +
          physgrad::local_href("runs/" + (fs::path(pages[k]).parent_path() / checked).string()) +
          "#" + std::to_string(n) + "\" width=\"600\" height=\"200\"></iframe>\n";
      expected.push_back(std::to_string(k) + " " + std::to_string(n) + " clean");
    }
  }
  std::ofstream(dir_ / "all.html") << "<!DOCTYPE html><html><body>\n"
                                   << frames << "</body></html>\n";
  Listener proxy;
  const fs::path log = dir_ / "chromium.log";
  ASSERT_EQ(run_chromium(dir_ / "all.html", dir_ / "chromium-profile", log,
                         "--proxy-server=http://127.0.0.1:" + std::to_string(proxy.port()) +
                             " --proxy-bypass-list='<-loopback>'"),
            0)
      << read_file(log);
  std::vector<std::string> requests = proxy.stop();
  std::erase_if(requests,
                [](const std::string& r) { return is_browser_service(requested_host(r)); });
  std::string asked;
  for (const std::string& r : requests) asked += r + "\n";
  EXPECT_EQ(requests.size(), 1u) << "requests other than the canary's:\n" << asked;
  EXPECT_EQ(requests.empty() ? "" : requested_host(requests[0]), "canary.physgrad.invalid")
      << "the proxy saw no canary: " << asked;

  const std::string console = read_file(log);
  std::size_t links = 0;
  for (const std::string& message : console_messages(console, "link")) {
    const std::size_t space = message.find(' '), second = message.find(' ', space + 1);
    expect_local_file(message.substr(second + 1), pages.at(std::stoul(message.substr(0, space))));
    ++links;
  }
  EXPECT_GE(links, 5u) << console;
  for (const std::string& message : console_messages(console, "scripts")) {
    // Scripts that run: the one added and, with the interactive comparison (one JSON block,
    // which it draws), its own; no event-handler attribute.
    const std::string seen = message.substr(message.find(' ', message.find(' ') + 1) + 1);
    EXPECT_TRUE(seen == "1 0 0 none" || seen == "2 1 0 true")
        << message << ": scripts and event handlers beyond the one added and the comparison's";
  }
  std::vector<std::string> after = console_messages(console, "after");
  std::sort(after.begin(), after.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(after, expected) << "a frame whose link ran a script or left the page (no message):\n"
                             << console;
}

}  // namespace
