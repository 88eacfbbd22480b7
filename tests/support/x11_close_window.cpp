// Test helper: closes an X window as a user does with the title bar's close button (a WM_DELETE_WINDOW
// message), without a window manager. Usage: x11_close_window TITLE_PREFIX SECONDS. Waits up to SECONDS for
// a top-level window whose name starts with TITLE_PREFIX; exits 0 once the message is sent, 1 otherwise.
#include <X11/Xatom.h>
#include <X11/Xlib.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

namespace {

Window find_window(Display* display, const std::string& prefix) {
  Window root = 0, parent = 0, *children = nullptr, found = 0;
  unsigned count = 0;
  if (!XQueryTree(display, DefaultRootWindow(display), &root, &parent, &children, &count)) return 0;
  for (unsigned i = 0; i < count && !found; ++i) {
    char* name = nullptr;
    if (XFetchName(display, children[i], &name) && name) {
      if (std::strncmp(name, prefix.c_str(), prefix.size()) == 0) found = children[i];
      XFree(name);
    }
  }
  if (children) XFree(children);
  return found;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: x11_close_window TITLE_PREFIX SECONDS\n");
    return 1;
  }
  Display* display = XOpenDisplay(nullptr);
  if (!display) {
    std::fprintf(stderr, "x11_close_window: cannot open the display\n");
    return 1;
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(std::atof(argv[2]));
  Window window = 0;
  while (!(window = find_window(display, argv[1])) && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  if (!window) {
    std::fprintf(stderr, "x11_close_window: no window named '%s...'\n", argv[1]);
    XCloseDisplay(display);
    return 1;
  }
  XEvent message{};
  message.xclient.type = ClientMessage;
  message.xclient.window = window;
  message.xclient.message_type = XInternAtom(display, "WM_PROTOCOLS", False);
  message.xclient.format = 32;
  message.xclient.data.l[0] = static_cast<long>(XInternAtom(display, "WM_DELETE_WINDOW", False));
  message.xclient.data.l[1] = CurrentTime;
  XSendEvent(display, window, False, NoEventMask, &message);
  XFlush(display);
  XCloseDisplay(display);
  std::printf("closed '%s...'\n", argv[1]);
  return 0;
}
