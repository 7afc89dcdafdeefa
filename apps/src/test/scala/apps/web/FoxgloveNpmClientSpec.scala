package apps.web

import java.io.File
import java.nio.charset.StandardCharsets
import java.nio.file.{Files, StandardCopyOption}

import scala.concurrent.duration._
import scala.util.Try

import akka.actor.testkit.typed.scaladsl.{LogCapturing, ScalaTestWithActorTestKit}
import org.scalatest.wordspec.AnyWordSpecLike
import spray.json._

import apps.zeromq.PythonEnv

/** The client of the Foxglove WebSocket protocol we did not write: `@foxglove/ws-protocol`'s FoxgloveClient from the
  * npm registry under Node (pinned, installed at test time under apps/target/), which subscribes to `/robot/1/status`
  * and `/gateway/datagrams` and decodes them with the advertised schema (protobufjs); and a bare WebSocket (`ws`)
  * offering `foxglove.sdk.v1` first, as the Foxglove SDK's viewers do, whose handshake and first message are checked
  * against the SDK's description of them (its handshake answers with `foxglove.sdk.v1`; its ServerInfo has a name,
  * capabilities from its list, and optional supportedEncodings, metadata and sessionId). Cancelled where Node, npm or
  * the registry are missing.
  */
class FoxgloveNpmClientSpec extends ScalaTestWithActorTestKit(WebDemo.config) with AnyWordSpecLike with LogCapturing {

  private lazy val demo = new WebDemo(system, WebSettings(system))

  override def afterAll(): Unit = {
    Try(demo.stop())
    super.afterAll()
  }

  /** The packages, pinned: the ws-protocol's last published client, its WebSocket for Node, the protobuf decoder. */
  private val Packages =
    """{"name":"naogateway-foxglove-npm-client","private":true,"dependencies":{"@foxglove/ws-protocol":"0.8.0",""" +
      """"ws":"8.18.3","protobufjs":"7.5.4"}}"""

  /** The capabilities the SDK's ServerInfo knows. */
  private val SdkCapabilities = Set("clientPublish", "parameters", "parametersSubscribe", "time", "services",
    "connectionGraph", "assets", "rangedPlayback")

  /** The folder with the packages installed and the script beside them, or why there is none. */
  private def install(): Either[String, File] = {
    val dir = new File(PythonEnv.root, "apps/target/foxglove-npm")
    dir.mkdirs()
    val log = new File(dir.getParentFile, "foxglove-npm-setup.log")
    val present = (cmd: String) => Try(PythonEnv.run(Seq(cmd, "--version"), 30.seconds, log)._1 == 0).getOrElse(false)
    if (!present("node")) Left("node is not installed")
    else if (!present("npm")) Left("npm is not installed")
    else {
      val manifest = new File(dir, "package.json")
      val stamp = new File(dir, "node_modules/.naogateway-installed")
      val current = Try(new String(Files.readAllBytes(stamp.toPath), StandardCharsets.UTF_8)).toOption
      val script = new File(dir, "npm-client.mjs")
      Files.copy(getClass.getResourceAsStream("/foxglove/npm-client.mjs"), script.toPath,
        StandardCopyOption.REPLACE_EXISTING)
      if (current.contains(Packages)) Right(dir)
      else {
        Files.write(manifest.toPath, Packages.getBytes(StandardCharsets.UTF_8))
        val (code, out) = PythonEnv.run(
          Seq("npm", "install", "--prefix", dir.getPath, "--no-audit", "--no-fund", "--no-package-lock", "--silent"),
          5.minutes, log)
        if (code != 0) Left(s"npm could not install the client (no package registry?):\n${out.takeRight(2000)}")
        else {
          Files.write(stamp.toPath, Packages.getBytes(StandardCharsets.UTF_8))
          Right(dir)
        }
      }
    }
  }

  "The Foxglove feed" should {
    "serve the npm registry's FoxgloveClient /robot/1/status and /gateway/datagrams decodable with the advertised " +
      "schema, and answer a client " +
      "offering foxglove.sdk.v1 with that name and the SDK's server info" in {
        val dir = install().fold(why => cancel(s"$why: the npm client test cannot run"), identity)
        val url = s"ws://127.0.0.1:${demo.address.getPort}/foxglove"
        val (code, out) = PythonEnv.run(Seq("node", new File(dir, "npm-client.mjs").getPath, url), 60.seconds,
          new File(dir.getParentFile, "foxglove-npm-client.log"))
        withClue(out) {
          code shouldBe 0
          val lines = out.linesIterator.filter(_.startsWith("{")).map(_.parseJson.asJsObject).toVector
          val client = lines.flatMap(_.fields.get("client")).head.asJsObject.fields
          client("protocol") shouldBe JsString(FoxgloveFeed.Subprotocol)
          client("topic") shouldBe JsString("/robot/1/status")
          client("encoding") shouldBe JsString("protobuf")
          client("schemaEncoding") shouldBe JsString("protobuf")
          client("schemaName") shouldBe JsString("naogateway.proto.Status")
          val status = client("status").asJsObject.fields
          status("activeRole") shouldBe JsString("keeper")
          status.keySet should contain("currentState")
          val nanos = client("timestamp").asInstanceOf[JsString].value.toLong
          math.abs(nanos / 1000000L - System.currentTimeMillis()) should be < 60000L

          // The gateway's tap as the recording holds it: a keep-alive robot 1 sent, byte for byte.
          val datagram = lines.flatMap(_.fields.get("datagram")).head.asJsObject.fields
          datagram("schemaName") shouldBe JsString("naogateway.proto.RecordedDatagram")
          val recorded = datagram("recorded").asJsObject.fields
          recorded("source").asInstanceOf[JsString].value should startWith("127.")
          val payload = java.util.Base64.getDecoder.decode(recorded("payload").asInstanceOf[JsString].value)
          naogateway.wire.MessageContents.decodeFrame(payload).map(_._2.robotId) shouldBe Right(1)

          val sdk = lines.flatMap(_.fields.get("sdk")).head.asJsObject.fields
          sdk("protocol") shouldBe JsString(FoxgloveFeed.SdkSubprotocol)
          sdk("binary") shouldBe JsFalse
          val info = sdk("first").asJsObject.fields
          info("op") shouldBe JsString("serverInfo")
          info("name") shouldBe a[JsString]
          val capabilities = info("capabilities").asInstanceOf[JsArray].elements
          all(capabilities.map(_.asInstanceOf[JsString].value)) should (be(a[String]) and not be empty)
          capabilities.map(_.asInstanceOf[JsString].value).toSet.subsetOf(SdkCapabilities) shouldBe true
          info.get("supportedEncodings").foreach(_.asInstanceOf[JsArray].elements.foreach(_ shouldBe a[JsString]))
          info.get("metadata").foreach(_.asJsObject.fields.values.foreach(_ shouldBe a[JsString]))
          info.get("sessionId").foreach(_ shouldBe a[JsString])
          (info.keySet -- Set("op", "name", "capabilities", "supportedEncodings", "metadata", "sessionId",
            "dataStartTime", "dataEndTime")) shouldBe empty
        }
      }
  }
}
