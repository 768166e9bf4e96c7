"""While the app opens (a first launch imports for many seconds), the terminal hears that it is
still opening, until the window is up."""

import io
import threading

from rollball_app.opening_notice import OpeningNotice


class Lines(io.StringIO):
    def __init__(self):
        super().__init__()
        self.said = threading.Event()

    def write(self, text):
        if text.strip():
            self.said.set()
        return super().write(text)


def test_says_it_is_still_opening_until_done():
    stream = Lines()
    notice = OpeningNotice(every=0.01, stream=stream).start()
    assert stream.said.wait(10)
    notice.done()
    notice._thread.join(10)
    assert not notice._thread.is_alive()
    said = stream.getvalue().splitlines()
    assert said and all(line.startswith("rollball: still opening the app (") and line.endswith(" s)")
                        for line in said)


def test_says_nothing_when_the_window_comes_at_once():
    stream = Lines()
    notice = OpeningNotice(every=60.0, stream=stream).start()
    notice.done()
    notice._thread.join(10)
    assert stream.getvalue() == ""
