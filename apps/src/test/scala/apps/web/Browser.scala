package apps.web

import java.io.File
import java.nio.file.{Files, Path}

import org.openqa.selenium.chrome.{ChromeDriver, ChromeDriverService, ChromeOptions}

/** The system's headless Chromium through its chromedriver, for the web view's tests and bench (never downloaded). */
object Browser {

  /** Chromium's own binary (Debian's /usr/bin/chromium is a wrapper script), and the driver of the same package. */
  private val Binaries =
    Vector("/usr/lib/chromium/chromium", "/usr/bin/chromium", "/usr/bin/chromium-browser").map(new File(_))
  private val Drivers = Vector("/usr/bin/chromedriver", "/usr/lib/chromium/chromedriver").map(new File(_))

  /** Why no browser can run here, if none can. */
  def missing: Option[String] =
    if (!Binaries.exists(_.canExecute))
      Some("no Chromium installed (Debian: apt-get install chromium chromium-driver; .ci/setup.d/browser.sh)")
    else if (!Drivers.exists(_.canExecute))
      Some("no chromedriver installed (Debian: apt-get install chromium-driver; .ci/setup.d/browser.sh)")
    else None

  /** A headless Chromium with a fresh profile of its own, which it deletes when `use` ends. */
  def withChromium[A](width: Int = 1400, height: Int = 1000)(use: ChromeDriver => A): A = {
    val profile: Path = Files.createTempDirectory("naogateway-chromium")
    val options = new ChromeOptions()
    options.setBinary(Binaries.find(_.canExecute).get)
    // Root needs --no-sandbox; the rest keep the browser off the network and quiet: only the gateway on loopback.
    options.addArguments(
      "--headless",
      "--no-sandbox",
      "--disable-gpu",
      "--disable-quic",
      "--no-first-run",
      "--disable-background-networking",
      "--disable-component-update",
      "--disable-sync",
      "--disable-dev-shm-usage",
      s"--user-data-dir=$profile",
      s"--window-size=$width,$height"
    )
    val service =
      new ChromeDriverService.Builder().usingDriverExecutable(Drivers.find(_.canExecute).get).usingAnyFreePort().build()
    val driver = new ChromeDriver(service, options)
    try use(driver)
    finally {
      driver.quit()
      service.stop()
      deleteTree(profile)
    }
  }

  private def deleteTree(p: Path): Unit =
    if (Files.exists(p)) {
      val walk = Files.walk(p)
      try walk.sorted(java.util.Comparator.reverseOrder[Path]()).forEach(f => f.toFile.delete())
      finally walk.close()
    }
}
