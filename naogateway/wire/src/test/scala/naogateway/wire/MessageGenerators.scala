package naogateway.wire

import com.google.protobuf.ByteString
import org.scalacheck.{Arbitrary, Gen}

import naogateway.proto._

/** ScalaCheck generators for every wire message of the project. */
object MessageGenerators {

  private val shortText: Gen[String] = Gen.choose(0, 24).flatMap(n => Gen.stringOfN(n, Gen.alphaNumChar))
  private val anyText: Gen[String] = Gen.choose(0, 24).flatMap(n => Gen.stringOfN(n, Arbitrary.arbitrary[Char]))
  private val uint32: Gen[Int] = Arbitrary.arbitrary[Int] // proto uint32 travels as Int bit pattern
  private def bytes(max: Int): Gen[ByteString] =
    Gen.choose(0, max).flatMap(n => Gen.listOfN(n, Arbitrary.arbitrary[Byte])).map(b => ByteString.copyFrom(b.toArray))

  val position: Gen[Position] = for {
    x <- Gen.option(Arbitrary.arbitrary[Int])
    y <- Gen.option(Arbitrary.arbitrary[Int])
    r <- Gen.option(Gen.choose(-3.2f, 3.2f))
  } yield Position(x, y, r)

  val status: Gen[Status] = for {
    timestamp <- Gen.option(Arbitrary.arbitrary[Long])
    team <- Gen.option(uint32)
    online <- Gen.option(uint32)
    pos <- Gen.option(position)
    belief <- Gen.option(Gen.choose(0.0, 1.0))
    agent <- Gen.option(anyText)
    role <- Gen.option(shortText)
    state <- Gen.option(shortText)
  } yield Status(timestamp, team, online, pos, belief, agent, role, state)

  val robotHealth: Gen[RobotHealth] = for {
    battery <- Gen.option(Gen.choose(9.0f, 12.6f))
    posture <- Gen.option(Gen.oneOf("sit", "stand", "crouch", "walking", "moving"))
    uptime <- Gen.option(uint32)
    boot <- Gen.option(uint32)
  } yield RobotHealth(battery, posture, uptime, boot)

  val servoState: Gen[ServoState] =
    for {
      id <- Gen.choose(0, 253)
      silent <- Gen.oneOf(false, false, true)
      position <- Gen.option(Gen.choose(0, 1023))
      load <- Gen.option(Gen.choose(-1023, 1023))
      voltage <- Gen.option(Gen.choose(0, 255))
      temperature <- Gen.option(Gen.choose(0, 255))
      error <- Gen.option(Gen.choose(0, 127))
    } yield
      if (silent) ServoState(id, silent = Some(true))
      else ServoState(id, position, load, voltage, temperature, error)

  val servoTelemetry: Gen[ServoTelemetry] = for {
    servos <- Gen.choose(0, 32).flatMap(Gen.listOfN(_, servoState))
    errors <- Gen.option(uint32)
  } yield ServoTelemetry(servos.toVector, errors)

  val debuggingOption: Gen[DebuggingOption] = for {
    name <- shortText
    kind <- Gen.option(Gen.oneOf(DebuggingOptionType.values))
    enabled <- Gen.option(Arbitrary.arbitrary[Boolean])
    description <- Gen.option(shortText)
  } yield DebuggingOption(name, kind, enabled, description)

  val optionNames: Gen[DebuggingOptionNames] = Gen.listOf(shortText).map(n => DebuggingOptionNames(n.take(8)))

  val debuggingCommands: Gen[DebuggingCommands] = for {
    pull <- Gen.option(Arbitrary.arbitrary[Boolean])
    push <- Gen.option(Gen.listOf(debuggingOption).map(o => DebuggingOptionList(o.take(8))))
    enable <- Gen.option(optionNames)
    disable <- Gen.option(optionNames)
  } yield DebuggingCommands(pull, push, enable, disable)

  val colour: Gen[Colour] = for {
    r <- Gen.choose(0, 255); g <- Gen.choose(0, 255); b <- Gen.choose(0, 255)
  } yield Colour(r, g, b)

  val shape: Gen[Shape] = for {
    kind <- Gen.oneOf(Shape.Kind.values)
    x1 <- Arbitrary.arbitrary[Int]
    y1 <- Arbitrary.arbitrary[Int]
    x2 <- Gen.option(Arbitrary.arbitrary[Int])
    y2 <- Gen.option(Arbitrary.arbitrary[Int])
    radius <- Gen.option(uint32)
    c <- Gen.option(colour)
    label <- Gen.option(shortText)
  } yield Shape(kind, x1, y1, x2, y2, radius, c, label)

  val debugData: Gen[DebugData] = {
    val text = anyText.map(t => DebugData.Data.Text(DebugText(t)))
    val table = Gen
      .listOf(Gen.zip(shortText, shortText))
      .map(rows => DebugData.Data.Table(DebugTable(rows.take(6).map { case (k, v) => DebugTable.Row(k, v) })))
    val plot = Gen
      .listOf(Gen.zip(shortText, Arbitrary.arbitrary[Float].suchThat(!_.isNaN)))
      .map(s => DebugData.Data.Plot(DebugPlot(s.take(6).map { case (n, v) => DebugPlot.Sample(n, v) })))
    val relative = Gen
      .listOf(Gen.zip(shortText, uint32, Gen.choose(-3.2f, 3.2f)))
      .map(o =>
        DebugData.Data.RelativePosition(DebugRelativePosition(o.take(6).map { case (n, d, a) =>
          DebugRelativePosition.RelativeObject(n, d, a)
        })))
    val field = Gen.listOf(shape).map(s => DebugData.Data.FieldDrawing(DebugFieldDrawing(s.take(6))))
    val image = for {
      w <- Gen.choose(0, 160)
      h <- Gen.choose(0, 120)
      f <- Gen.option(Gen.oneOf(DebugImage.Format.values))
      px <- Gen.option(bytes(200))
      overlay <- Gen.listOf(shape)
    } yield DebugData.Data.Image(DebugImage(w, h, f, px, overlay.take(4)))
    for {
      option <- shortText
      timestamp <- Gen.option(Arbitrary.arbitrary[Long])
      data <- Gen.oneOf(text, table, plot, relative, field, image)
    } yield DebugData(option, timestamp, data)
  }

  val region: Gen[HaViMoRegion] = for {
    index <- Gen.choose(1, 255)
    colour <- Gen.choose(0, 255)
    pixels <- Gen.choose(0, 0xffff)
    sumX <- Gen.choose(0L, 0xffffffffL)
    sumY <- Gen.choose(0L, 0xffffffffL)
    box <- Gen.listOfN(4, Gen.choose(0, 255))
  } yield HaViMoRegion(index, colour, pixels, sumX, sumY, box(0), box(1), box(2), box(3))

  val regionFrame: Gen[HaViMoRegionFrame] = for {
    frame <- uint32
    timestamp <- Gen.option(Arbitrary.arbitrary[Long])
    regions <- Gen.choose(0, HaViMo.MaxRegions).flatMap(Gen.listOfN(_, region))
  } yield HaViMoRegionFrame(frame, timestamp, Some(ByteString.copyFrom(HaViMo.encodeRegions(regions).toOption.get)))

  val gridCells: Gen[Array[Byte]] = Gen.listOfN(HaViMo.GridCells, Arbitrary.arbitrary[Byte]).map(_.toArray)

  val gridFrame: Gen[HaViMoGridFrame] = for {
    frame <- uint32
    timestamp <- Gen.option(Arbitrary.arbitrary[Long])
    cells <- gridCells
  } yield HaViMoGridFrame(frame, timestamp, ByteString.copyFrom(cells))

  val mixedValue: Gen[MixedValue] = {
    def level(depth: Int): Gen[MixedValue] = {
      val leaves = Gen.oneOf(
        anyText.map(s => MixedValue(string = Some(s))),
        uint32.map(i => MixedValue(int = Some(i))),
        Arbitrary.arbitrary[Float].suchThat(!_.isNaN).map(f => MixedValue(float = Some(f))),
        bytes(32).map(b => MixedValue(binary = Some(b))),
        Arbitrary.arbitrary[Boolean].map(b => MixedValue(bool = Some(b)))
      )
      if (depth <= 0) leaves
      else Gen.frequency(4 -> leaves, 1 -> Gen.listOf(level(depth - 1)).map(a => MixedValue(array = a.take(4))))
    }
    level(2)
  }

  val request: Gen[Request] = for {
    module <- shortText
    method <- shortText
    params <- Gen.listOf(mixedValue)
    callId <- Gen.option(uint32)
  } yield Request(module, method, params.take(4), callId)

  val response: Gen[Response] = for {
    value <- Gen.option(mixedValue)
    error <- Gen.option(anyText)
    callId <- Gen.option(uint32)
  } yield Response(value, error, callId)

  /** Contents with any combination of the known extensions, small enough for one frame most of the time. */
  val contents: Gen[MessageContents] = for {
    robotId <- Arbitrary.arbitrary[Int]
    s <- Gen.option(status)
    h <- Gen.option(robotHealth)
    dc <- Gen.option(debuggingCommands)
    dd <- Gen.option(debugData)
    hr <- Gen.option(regionFrame)
    hg <- Gen.option(gridFrame)
    rq <- Gen.option(request)
    rs <- Gen.option(response)
    st <- Gen.option(servoTelemetry)
  } yield MessageContents(robotId, s, h, dc, dd, hr, hg, rq, rs, st)

  val headerForm: Gen[HeaderForm] = Gen.oneOf(HeaderForm.Legacy, HeaderForm.Compact)

  val anyBytes: Gen[Array[Byte]] =
    Gen.choose(0, 1500).flatMap(n => Gen.listOfN(n, Arbitrary.arbitrary[Byte])).map(_.toArray)
}
