package naogateway.sim

import com.google.protobuf.ByteString

import naogateway.proto._
import naogateway.sim.bus.BusWork
import naogateway.wire._

/** What the simulated firmware sends on its debug options (docs/protocol.md 8): the non-camera options' data, and the
  * camera's frames read over the robot's emulated bus. Pure, beside [[RobotFirmware]].
  */
private[sim] object FirmwareDebug {

  /** The debug data of the enabled non-camera options, at the firmware's time. */
  def debugData(s: FirmwareState): Vector[DebugData] = {
    val ts = Some(s.uptimeMillis)
    val (ahead, left) = s.pose.relative(s.settings.scene.ballX, s.settings.scene.ballY)
    s.debugEnabled.toVector.sorted.collect {
      case o @ "status.text" => DebugData(o, ts,
          DebugData.Data.Text(DebugText(s"posture ${s.posture.name}, battery ${"%.2f".format(s.battery)} V")))
      case o @ "status.table" =>
        DebugData(
          o,
          ts,
          DebugData.Data.Table(DebugTable(Seq(
                DebugTable.Row("battery", "%.2f".format(s.battery)),
                DebugTable.Row("posture", s.posture.name),
                DebugTable.Row("uptime", s"${s.uptimeMillis} ms"))))
        )
      case o @ "motion.plot" =>
        val w = s.walk.getOrElse(Walk(0, 0, 0, 0))
        DebugData(
          o,
          ts,
          DebugData.Data.Plot(DebugPlot(Seq(
                DebugPlot.Sample("vx", w.vx.toFloat), DebugPlot.Sample("vy", w.vy.toFloat),
                DebugPlot.Sample("omega", w.omega.toFloat))))
        )
      case o @ "world.field" =>
        DebugData(
          o,
          ts,
          DebugData.Data.FieldDrawing(DebugFieldDrawing(Seq(
                Shape(Shape.Kind.CIRCLE, (s.pose.x * 1000).toInt, (s.pose.y * 1000).toInt, radius = Some(150),
                  label = Some("robot")),
                Shape(Shape.Kind.CIRCLE, (s.settings.scene.ballX * 1000).toInt, (s.settings.scene.ballY * 1000).toInt,
                  radius = Some(50), label = Some("ball"))
              )))
        )
      case o @ "world.relative" =>
        DebugData(
          o,
          ts,
          DebugData.Data.RelativePosition(DebugRelativePosition(Seq(
                DebugRelativePosition.RelativeObject("ball", (math.hypot(ahead, left) * 1000).toInt,
                  math.atan2(left, ahead).toFloat))))
        )
    }
  }

  /** The camera frames of one camera cycle, and the firmware after it. */
  // The camera is read over the bus (docs/protocol.md 6.9): the frame holds the capture started a cycle earlier, and
  // no frame goes out while the camera is still busy with it.
  def cameraFrames(s: FirmwareState): (FirmwareState, Vector[Array[Byte]]) = {
    val view = Scene.view(s.cameraView, s.settings.scene, s.pose, s.head)
    val withGrid = s.debugEnabled("havimo.grid") || s.debugEnabled("camera.image")
    val (bus, read) = BusWork.cameraCycle(s.bus.advance(s.now).withVolts(s.battery).seeing(view.regions), withGrid)
    read match {
      case None => (s.copy(bus = bus, cameraView = Some(view)), Vector.empty)
      case Some(captured) =>
        val frame = s.frame + 1
        val ts = Some(s.uptimeMillis)
        val out = Vector.newBuilder[Array[Byte]]
        if (s.debugEnabled("havimo.regions"))
          out += RobotFirmware.encode(s,
            MessageContents(s.settings.robotId,
              havimoRegions = Some(HaViMoRegionFrame(frame, ts, Some(ByteString.copyFrom(captured.records))))))
        captured.grid.foreach { grid =>
          if (s.debugEnabled("havimo.grid"))
            out += RobotFirmware.encode(s,
              MessageContents(s.settings.robotId,
                havimoGrid = Some(HaViMoGridFrame(frame, ts, ByteString.copyFrom(grid)))))
          if (s.debugEnabled("camera.image")) {
            val regions = HaViMo.decodeRegions(captured.records).getOrElse(Vector.empty)
            val shapes = regions.map(r =>
              Shape(Shape.Kind.RECTANGLE, r.minX, r.minY, Some(r.maxX), Some(r.maxY),
                label = Some(s"colour ${r.colour}")))
            val image = DebugImage(32, 24, Some(DebugImage.Format.COLOUR_CLASSES),
              Some(ByteString.copyFrom(grid.map(b => (b & 0x0f).toByte))), shapes)
            out += RobotFirmware.encode(s,
              MessageContents(s.settings.robotId,
                debugData = Some(DebugData("camera.image", ts, DebugData.Data.Image(image)))))
          }
        }
        (s.copy(frame = frame, bus = bus, cameraView = Some(view)), out.result())
    }
  }
}
